#include "rail_vehicle_node/force_element.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "rail_vehicle_node/joint.hpp"

namespace rail::vehicle {

void ForceElement::applyForceAt(const VehicleData& data, int body, const Vector3& f_in_world, const Vector3& p_in_world,
                                Eigen::Ref<Eigen::VectorXd> g) {
  if (body == kGround) return;
  const BodyKinematics& b = data.bodies[static_cast<std::size_t>(body)];
  g.segment<3>(6 * body) += f_in_world;
  g.segment<3>(6 * body + 3) += b.A.transpose() * (p_in_world - b.r).cross(f_in_world);
}

void ForceElement::applyMoment(const VehicleData& data, int body, const Vector3& n_in_world,
                               Eigen::Ref<Eigen::VectorXd> g) {
  if (body == kGround) return;
  const BodyKinematics& b = data.bodies[static_cast<std::size_t>(body)];
  g.segment<3>(6 * body + 3) += b.A.transpose() * n_in_world;
}

void ForceElement::couplingGroups(std::vector<std::vector<int>>& groups) const {
  std::vector<int> group;
  if (body_i_ != kGround) group.push_back(body_i_);
  if (body_j_ != kGround && body_j_ != body_i_) group.push_back(body_j_);
  if (!group.empty()) groups.push_back(group);
}

void ForceElement::pointState(const VehicleData& data, int body, const Vector3& s_in_body, Vector3& p_in_world,
                              Vector3& v_in_world) {
  if (body == kGround) {
    p_in_world = s_in_body;
    v_in_world.setZero();
    return;
  }
  const BodyKinematics& b = data.bodies[static_cast<std::size_t>(body)];
  const Vector3 arm = b.A * s_in_body;
  p_in_world = b.r + arm;
  v_in_world = b.r_dot + b.omega_world.cross(arm);
}

// ---------------------------------------------------------------------------------------------------------

Bushing::Bushing(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j,
                 const Matrix3& R_bushing_to_i, const Matrix3& R_bushing_to_j, const Parameters& parameters)
    : ForceElement(std::move(name), body_i, body_j),
      s_in_i_(s_in_i),
      s_in_j_(s_in_j),
      R_bushing_to_i_(R_bushing_to_i),
      R_bushing_to_j_(R_bushing_to_j),
      parameters_(parameters) {
  const auto check = [this](const Vector3& v, const char* what) {
    if ((v.array() < 0.0).any() || !v.allFinite()) {
      std::ostringstream os;
      os << "bushing " << this->name() << ": " << what << " must be finite and >= 0, got [" << v.transpose() << "]";
      throw std::runtime_error(os.str());
    }
  };
  check(parameters.stiffness, "stiffness");
  check(parameters.damping, "damping");
  check(parameters.rotational_stiffness, "rotational_stiffness");
  check(parameters.rotational_damping, "rotational_damping");
  has_rotational_ =
      (parameters.rotational_stiffness.array() > 0.0).any() || (parameters.rotational_damping.array() > 0.0).any();
}

void Bushing::evaluateLocal(const VehicleData& data, Vector3& deflection, Vector3& force_on_j_local) const {
  Vector3 p_i, v_i, p_j, v_j;
  pointState(data, bodyI(), s_in_i_, p_i, v_i);
  pointState(data, bodyJ(), s_in_j_, p_j, v_j);
  const Matrix3 A_i = bodyI() == kGround ? Matrix3::Identity() : data.bodies[static_cast<std::size_t>(bodyI())].A;
  const Vector3 omega_i =
      bodyI() == kGround ? Vector3::Zero() : data.bodies[static_cast<std::size_t>(bodyI())].omega_world;
  const Matrix3 R_bushing_to_world = A_i * R_bushing_to_i_;
  const Vector3 delta = p_j - p_i;
  deflection = R_bushing_to_world.transpose() * delta - parameters_.free_offset;
  // Rate of the deflection measured in the rotating bushing frame.
  const Vector3 deflection_rate = R_bushing_to_world.transpose() * (v_j - v_i - omega_i.cross(delta));
  force_on_j_local = parameters_.preload - parameters_.stiffness.cwiseProduct(deflection) -
                     parameters_.damping.cwiseProduct(deflection_rate);
}

void Bushing::addForces(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> g) const {
  Vector3 deflection, f_local;
  evaluateLocal(data, deflection, f_local);
  const Matrix3 A_i = bodyI() == kGround ? Matrix3::Identity() : data.bodies[static_cast<std::size_t>(bodyI())].A;
  const Matrix3 R_bushing_to_world = A_i * R_bushing_to_i_;
  Vector3 p_j, v_j;
  pointState(data, bodyJ(), s_in_j_, p_j, v_j);
  const Vector3 f_world = R_bushing_to_world * f_local;
  applyForceAt(data, bodyJ(), f_world, p_j, g);
  applyForceAt(data, bodyI(), -f_world, p_j, g);

  if (has_rotational_) {
    const Matrix3 A_j = bodyJ() == kGround ? Matrix3::Identity() : data.bodies[static_cast<std::size_t>(bodyJ())].A;
    const Vector3 omega_i =
        bodyI() == kGround ? Vector3::Zero() : data.bodies[static_cast<std::size_t>(bodyI())].omega_world;
    const Vector3 omega_j =
        bodyJ() == kGround ? Vector3::Zero() : data.bodies[static_cast<std::size_t>(bodyJ())].omega_world;
    const Matrix3 R_rel = R_bushing_to_world.transpose() * (A_j * R_bushing_to_j_);
    const Vector3 theta = rotationVectorFromRotation(R_rel);
    const Vector3 omega_rel = R_bushing_to_world.transpose() * (omega_j - omega_i);
    const Vector3 torque_local =
        -parameters_.rotational_stiffness.cwiseProduct(theta) - parameters_.rotational_damping.cwiseProduct(omega_rel);
    const Vector3 torque_world = R_bushing_to_world * torque_local;
    applyMoment(data, bodyJ(), torque_world, g);
    applyMoment(data, bodyI(), -torque_world, g);
  }
}

double Bushing::potentialEnergy(const VehicleData& data) const {
  Vector3 deflection, f_local;
  evaluateLocal(data, deflection, f_local);
  double energy =
      0.5 * deflection.dot(parameters_.stiffness.cwiseProduct(deflection)) - parameters_.preload.dot(deflection);
  if (has_rotational_) {
    const Matrix3 A_i = bodyI() == kGround ? Matrix3::Identity() : data.bodies[static_cast<std::size_t>(bodyI())].A;
    const Matrix3 A_j = bodyJ() == kGround ? Matrix3::Identity() : data.bodies[static_cast<std::size_t>(bodyJ())].A;
    const Vector3 theta = rotationVectorFromRotation((A_i * R_bushing_to_i_).transpose() * (A_j * R_bushing_to_j_));
    energy += 0.5 * theta.dot(parameters_.rotational_stiffness.cwiseProduct(theta));
  }
  return energy;
}

// ---------------------------------------------------------------------------------------------------------

PointToPointSpringDamper::PointToPointSpringDamper(std::string name, int body_i, int body_j, const Vector3& s_in_i,
                                                   const Vector3& s_in_j, double stiffness, double damping,
                                                   double free_length, double preload)
    : ForceElement(std::move(name), body_i, body_j),
      s_in_i_(s_in_i),
      s_in_j_(s_in_j),
      k_(stiffness),
      c_(damping),
      free_length_(free_length),
      preload_(preload) {
  if (!(stiffness >= 0.0) || !(damping >= 0.0) || !(free_length >= 0.0) || !std::isfinite(stiffness) ||
      !std::isfinite(damping) || !std::isfinite(free_length) || !std::isfinite(preload)) {
    std::ostringstream os;
    os << "point-to-point element " << this->name()
       << ": stiffness, damping and free length must be finite and >= 0, got " << stiffness << ", " << damping << ", "
       << free_length;
    throw std::runtime_error(os.str());
  }
}

void PointToPointSpringDamper::addForces(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> g) const {
  Vector3 p_i, v_i, p_j, v_j;
  pointState(data, bodyI(), s_in_i_, p_i, v_i);
  pointState(data, bodyJ(), s_in_j_, p_j, v_j);
  const Vector3 delta = p_j - p_i;
  const double length = delta.norm();
  if (length < 1e-12) return;  // direction undefined; the element carries no force at zero length
  const Vector3 u = delta / length;
  const double length_rate = u.dot(v_j - v_i);
  const double tension = k_ * (length - free_length_) + c_ * length_rate + preload_;
  applyForceAt(data, bodyI(), tension * u, p_i, g);
  applyForceAt(data, bodyJ(), -tension * u, p_j, g);
}

double PointToPointSpringDamper::potentialEnergy(const VehicleData& data) const {
  Vector3 p_i, v_i, p_j, v_j;
  pointState(data, bodyI(), s_in_i_, p_i, v_i);
  pointState(data, bodyJ(), s_in_j_, p_j, v_j);
  const double length = (p_j - p_i).norm();
  return 0.5 * k_ * (length - free_length_) * (length - free_length_) + preload_ * length;
}

// ---------------------------------------------------------------------------------------------------------

BumpStop::BumpStop(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j,
                   const Vector3& axis_in_i, std::vector<double> deflections, std::vector<double> forces)
    : ForceElement(std::move(name), body_i, body_j),
      s_in_i_(s_in_i),
      s_in_j_(s_in_j),
      deflections_(std::move(deflections)),
      forces_(std::move(forces)) {
  if (axis_in_i.norm() < 1e-12) throw std::runtime_error("bump stop " + this->name() + ": zero-length axis");
  axis_in_i_ = axis_in_i.normalized();
  if (deflections_.size() < 2 || deflections_.size() != forces_.size()) {
    throw std::runtime_error("bump stop " + this->name() + ": force table needs >= 2 (deflection, force) rows, got " +
                             std::to_string(deflections_.size()));
  }
  if (!(deflections_.front() >= 0.0) || forces_.front() != 0.0) {
    std::ostringstream os;
    os << "bump stop " << this->name() << ": first table row must be (clearance >= 0, 0), got (" << deflections_.front()
       << ", " << forces_.front() << ")";
    throw std::runtime_error(os.str());
  }
  for (std::size_t k = 1; k < deflections_.size(); ++k) {
    if (!(deflections_[k] > deflections_[k - 1]) || !(forces_[k] >= forces_[k - 1])) {
      std::ostringstream os;
      os << "bump stop " << this->name() << ": table row " << k
         << " must increase in deflection and not decrease in force, got (" << deflections_[k] << ", " << forces_[k]
         << ") after (" << deflections_[k - 1] << ", " << forces_[k - 1] << ")";
      throw std::runtime_error(os.str());
    }
  }
}

double BumpStop::forceAt(double x) const {
  if (x <= deflections_.front()) return 0.0;
  const std::size_t n = deflections_.size();
  std::size_t k = 1;
  while (k < n - 1 && x > deflections_[k]) ++k;
  const double slope = (forces_[k] - forces_[k - 1]) / (deflections_[k] - deflections_[k - 1]);
  return forces_[k - 1] + slope * (x - deflections_[k - 1]);
}

double BumpStop::deflection(const VehicleData& data, Vector3& axis_in_world, Vector3& p_j) const {
  Vector3 p_i, v_i, v_j;
  pointState(data, bodyI(), s_in_i_, p_i, v_i);
  pointState(data, bodyJ(), s_in_j_, p_j, v_j);
  axis_in_world =
      bodyI() == kGround ? axis_in_i_ : Vector3(data.bodies[static_cast<std::size_t>(bodyI())].A * axis_in_i_);
  return axis_in_world.dot(p_j - p_i);
}

void BumpStop::addForces(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> g) const {
  Vector3 axis, p_j;
  const double d = deflection(data, axis, p_j);
  const double magnitude = forceAt(std::abs(d));
  if (magnitude == 0.0) return;
  const Vector3 f_on_j = -(d > 0.0 ? magnitude : -magnitude) * axis;
  applyForceAt(data, bodyJ(), f_on_j, p_j, g);
  applyForceAt(data, bodyI(), -f_on_j, p_j, g);
}

double BumpStop::potentialEnergy(const VehicleData& data) const {
  Vector3 axis, p_j;
  const double x = std::abs(deflection(data, axis, p_j));
  if (x <= deflections_.front()) return 0.0;
  // Exact integral of the piecewise-linear force from the clearance to x.
  double energy = 0.0;
  const std::size_t n = deflections_.size();
  for (std::size_t k = 1; k < n; ++k) {
    const double a = deflections_[k - 1];
    const double b = (k == n - 1) ? x : std::min(x, deflections_[k]);
    if (b <= a) break;
    energy += 0.5 * (forceAt(a) + forceAt(b)) * (b - a);
  }
  return energy;
}

}  // namespace rail::vehicle
