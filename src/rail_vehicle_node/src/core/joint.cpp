#include "rail_vehicle_node/joint.hpp"

#include <stdexcept>

namespace rail::vehicle {
namespace {

const BodyKinematics& groundKinematics() {
  static const BodyKinematics kGroundKinematics{};
  return kGroundKinematics;
}

const BodyKinematics& kinematicsOf(const VehicleData& data, int body) {
  return body == kGround ? groundKinematics() : data.bodies[static_cast<std::size_t>(body)];
}

// Unit vector perpendicular to the unit vector h.
Vector3 anyPerpendicular(const Vector3& h) {
  const Vector3 trial = std::abs(h.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
  return h.cross(trial).normalized();
}

}  // namespace

void Joint::sphericalRows(const VehicleData& data, const Vector3& s_in_i, const Vector3& s_in_j, int row,
                          Eigen::Ref<Eigen::VectorXd> phi, Eigen::Ref<Eigen::MatrixXd> phi_v_rows,
                          Eigen::Ref<Eigen::VectorXd> gamma) const {
  const BodyKinematics& bi = kinematicsOf(data, bodyI());
  const BodyKinematics& bj = kinematicsOf(data, bodyJ());
  phi.segment<3>(row) = bi.r + bi.A * s_in_i - bj.r - bj.A * s_in_j;
  // Point velocity r_dot + A (omega' x s) = r_dot - A s~ omega'.
  phi_v_rows.block<3, 3>(row, 6 * bodyI()).setIdentity();
  phi_v_rows.block<3, 3>(row, 6 * bodyI() + 3) = -bi.A * skew(s_in_i);
  const Vector3 centripetal_i = bi.A * bi.omega_body.cross(bi.omega_body.cross(s_in_i));
  Vector3 centripetal_j = Vector3::Zero();
  if (bodyJ() != kGround) {
    phi_v_rows.block<3, 3>(row, 6 * bodyJ()) = -Matrix3::Identity();
    phi_v_rows.block<3, 3>(row, 6 * bodyJ() + 3) = bj.A * skew(s_in_j);
    centripetal_j = bj.A * bj.omega_body.cross(bj.omega_body.cross(s_in_j));
  }
  gamma.segment<3>(row) = -centripetal_i + centripetal_j;
}

void Joint::perpendicularRow(const VehicleData& data, const Vector3& a_in_i, const Vector3& a_in_j, int row,
                             Eigen::Ref<Eigen::VectorXd> phi, Eigen::Ref<Eigen::MatrixXd> phi_v_rows,
                             Eigen::Ref<Eigen::VectorXd> gamma) const {
  const BodyKinematics& bi = kinematicsOf(data, bodyI());
  const BodyKinematics& bj = kinematicsOf(data, bodyJ());
  const Vector3 a_i = bi.A * a_in_i;
  const Vector3 a_j = bj.A * a_in_j;
  phi[row] = a_i.dot(a_j);
  // d/dt (A a') = A (omega' x a'), so d(a_i . a_j)/dt = omega'_i . (a'_i x A_i^T a_j) + (same for j).
  phi_v_rows.block<1, 3>(row, 6 * bodyI() + 3) = a_in_i.cross(bi.A.transpose() * a_j).transpose();
  const Vector3 a_i_dot = bi.A * bi.omega_body.cross(a_in_i);
  const Vector3 a_i_ddot_vel = bi.A * bi.omega_body.cross(bi.omega_body.cross(a_in_i));
  Vector3 a_j_dot = Vector3::Zero();
  Vector3 a_j_ddot_vel = Vector3::Zero();
  if (bodyJ() != kGround) {
    phi_v_rows.block<1, 3>(row, 6 * bodyJ() + 3) = a_in_j.cross(bj.A.transpose() * a_i).transpose();
    a_j_dot = bj.A * bj.omega_body.cross(a_in_j);
    a_j_ddot_vel = bj.A * bj.omega_body.cross(bj.omega_body.cross(a_in_j));
  }
  gamma[row] = -(a_j.dot(a_i_ddot_vel) + 2.0 * a_i_dot.dot(a_j_dot) + a_i.dot(a_j_ddot_vel));
}

SphericalJoint::SphericalJoint(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j)
    : Joint(std::move(name), body_i, body_j), s_in_i_(s_in_i), s_in_j_(s_in_j) {}

void SphericalJoint::evaluate(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> phi,
                              Eigen::Ref<Eigen::MatrixXd> phi_v_rows, Eigen::Ref<Eigen::VectorXd> gamma) const {
  sphericalRows(data, s_in_i_, s_in_j_, 0, phi, phi_v_rows, gamma);
}

RevoluteJoint::RevoluteJoint(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j,
                             const Vector3& axis_in_i, const Vector3& axis_in_j)
    : Joint(std::move(name), body_i, body_j), s_in_i_(s_in_i), s_in_j_(s_in_j) {
  if (axis_in_i.norm() < 1e-12 || axis_in_j.norm() < 1e-12) {
    throw std::runtime_error("revolute joint " + this->name() + ": zero-length axis");
  }
  const Vector3 h_i = axis_in_i.normalized();
  f_in_i_ = anyPerpendicular(h_i);
  g_in_i_ = h_i.cross(f_in_i_);
  h_in_j_ = axis_in_j.normalized();
}

void RevoluteJoint::evaluate(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> phi,
                             Eigen::Ref<Eigen::MatrixXd> phi_v_rows, Eigen::Ref<Eigen::VectorXd> gamma) const {
  sphericalRows(data, s_in_i_, s_in_j_, 0, phi, phi_v_rows, gamma);
  perpendicularRow(data, f_in_i_, h_in_j_, 3, phi, phi_v_rows, gamma);
  perpendicularRow(data, g_in_i_, h_in_j_, 4, phi, phi_v_rows, gamma);
}

FixedJoint::FixedJoint(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j,
                       const Matrix3& R_joint_to_i, const Matrix3& R_joint_to_j)
    : Joint(std::move(name), body_i, body_j),
      s_in_i_(s_in_i),
      s_in_j_(s_in_j),
      R_joint_to_i_(R_joint_to_i),
      R_joint_to_j_(R_joint_to_j) {}

void FixedJoint::evaluate(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> phi,
                          Eigen::Ref<Eigen::MatrixXd> phi_v_rows, Eigen::Ref<Eigen::VectorXd> gamma) const {
  sphericalRows(data, s_in_i_, s_in_j_, 0, phi, phi_v_rows, gamma);
  // x_i . y_j, y_i . z_j, z_i . x_j: independent to first order about the aligned configuration.
  perpendicularRow(data, R_joint_to_i_.col(0), R_joint_to_j_.col(1), 3, phi, phi_v_rows, gamma);
  perpendicularRow(data, R_joint_to_i_.col(1), R_joint_to_j_.col(2), 4, phi, phi_v_rows, gamma);
  perpendicularRow(data, R_joint_to_i_.col(2), R_joint_to_j_.col(0), 5, phi, phi_v_rows, gamma);
}

}  // namespace rail::vehicle
