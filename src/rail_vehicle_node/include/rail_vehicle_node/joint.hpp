// Joints as kinematic constraints Phi(q) = 0 between two bodies (or a body and the ground).
//
// Velocities are v = [r_dot (world); omega' (body frame)] per body, so a joint provides Phi, the rows of
// Phi_v = dPhi_dot/dv (the constraint Jacobian in velocity coordinates) and gamma, where the second
// derivative reads Phi_v * v_dot = gamma. Attachment vectors are constant in the body frames.
// To add a joint type, derive from Joint; the model calls Evaluate() once per right-hand side.
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>

#include "rail_vehicle_node/rigid_math.hpp"
#include "rail_vehicle_node/vehicle_data.hpp"

namespace rail::vehicle {

// Body index that stands for the fixed ground frame (identity pose, at rest).
constexpr int kGround = -1;

class Joint {
 public:
  Joint(std::string name, int body_i, int body_j) : name_(std::move(name)), body_i_(body_i), body_j_(body_j) {}
  virtual ~Joint() = default;

  const std::string& name() const { return name_; }
  int bodyI() const { return body_i_; }
  int bodyJ() const { return body_j_; }  // may be kGround

  // Number of scalar constraint equations.
  virtual int size() const = 0;

  // Writes Phi (size()), this joint's rows of Phi_v (size() x 6n; only the body_i / body_j blocks are
  // written, the rest must stay zero) and gamma (size()), from data.bodies (already evaluated).
  virtual void evaluate(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> phi,
                        Eigen::Ref<Eigen::MatrixXd> phi_v_rows, Eigen::Ref<Eigen::VectorXd> gamma) const = 0;

 protected:
  // Building blocks, each writing `rows` equations starting at `row`.
  // Spherical (3 rows): r_i + A_i s_i - r_j - A_j s_j = 0.
  void sphericalRows(const VehicleData& data, const Vector3& s_in_i, const Vector3& s_in_j, int row,
                     Eigen::Ref<Eigen::VectorXd> phi, Eigen::Ref<Eigen::MatrixXd> phi_v_rows,
                     Eigen::Ref<Eigen::VectorXd> gamma) const;
  // Dot-1 (1 row): (A_i a_i) . (A_j a_j) = 0.
  void perpendicularRow(const VehicleData& data, const Vector3& a_in_i, const Vector3& a_in_j, int row,
                        Eigen::Ref<Eigen::VectorXd> phi, Eigen::Ref<Eigen::MatrixXd> phi_v_rows,
                        Eigen::Ref<Eigen::VectorXd> gamma) const;

 private:
  std::string name_;
  int body_i_;
  int body_j_;
};

// Spherical joint: a point of body i coincides with a point of body j (3 equations).
class SphericalJoint : public Joint {
 public:
  // s_in_i, s_in_j: the joint point in each body frame, from the centre of mass [m].
  SphericalJoint(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j);
  int size() const override { return 3; }
  void evaluate(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> phi, Eigen::Ref<Eigen::MatrixXd> phi_v_rows,
                Eigen::Ref<Eigen::VectorXd> gamma) const override;

 private:
  Vector3 s_in_i_, s_in_j_;
};

// Revolute joint: spherical plus the axis h fixed in both bodies kept parallel (5 equations).
class RevoluteJoint : public Joint {
 public:
  // axis_in_i, axis_in_j: the joint axis in each body frame (normalised here).
  RevoluteJoint(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j,
                const Vector3& axis_in_i, const Vector3& axis_in_j);
  int size() const override { return 5; }
  void evaluate(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> phi, Eigen::Ref<Eigen::MatrixXd> phi_v_rows,
                Eigen::Ref<Eigen::VectorXd> gamma) const override;

 private:
  Vector3 s_in_i_, s_in_j_;
  Vector3 f_in_i_, g_in_i_;  // two unit vectors of body i perpendicular to its axis
  Vector3 h_in_j_;           // the axis in body j
};

// Fixed (weld) joint: no relative motion (6 equations). With body_j = kGround it fixes a body in space.
class FixedJoint : public Joint {
 public:
  // R_joint_to_i, R_joint_to_j: orientation of one common joint frame in each body frame.
  FixedJoint(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j,
             const Matrix3& R_joint_to_i, const Matrix3& R_joint_to_j);
  int size() const override { return 6; }
  void evaluate(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> phi, Eigen::Ref<Eigen::MatrixXd> phi_v_rows,
                Eigen::Ref<Eigen::VectorXd> gamma) const override;

 private:
  Vector3 s_in_i_, s_in_j_;
  Matrix3 R_joint_to_i_, R_joint_to_j_;
};

}  // namespace rail::vehicle
