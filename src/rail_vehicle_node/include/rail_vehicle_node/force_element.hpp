// Force elements: contributions to the generalised force vector g between two bodies (or a body and the
// ground, body index kGround).
//
// g holds per body [f (world frame, N); n' (body frame, N m, about the centre of mass)]. Attachment points
// are constant vectors in the body frames, from the centre of mass. To add a force law (e.g. a wheel-rail
// contact evaluated inside the right-hand side), derive from ForceElement.
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

#include "rail_vehicle_node/rigid_math.hpp"
#include "rail_vehicle_node/vehicle_data.hpp"

namespace rail::vehicle {

class ForceElement {
 public:
  ForceElement(std::string name, int body_i, int body_j) : name_(std::move(name)), body_i_(body_i), body_j_(body_j) {}
  virtual ~ForceElement() = default;

  const std::string& name() const { return name_; }
  int bodyI() const { return body_i_; }
  int bodyJ() const { return body_j_; }

  // Adds this element's forces to g (6n) from data.bodies (already evaluated). No allocation.
  virtual void addForces(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> g) const = 0;

  // Stored elastic energy [J] (0 for purely dissipative elements).
  virtual double potentialEnergy(const VehicleData& data) const = 0;

  // Groups of bodies (ground left out) such that the forces on a group's bodies depend on the states of
  // that group only; appended to `groups` (building time, for the Jacobian's sparsity). Default: one group
  // {body_i, body_j}.
  virtual void couplingGroups(std::vector<std::vector<int>>& groups) const;
  // Work state kept between evaluations (warm starts, memories), saved before and restored after the
  // perturbed evaluations of a difference-quotient Jacobian so that it leaves the run unchanged. No
  // allocation. Default: none.
  virtual void saveWorkState() const {}
  virtual void restoreWorkState() const {}
  // The integrator accepted a step at the state of the latest evaluation: work state that must only hold
  // accepted history (the contacts' impact memories) takes it now. No allocation. Default: nothing.
  virtual void acceptStep() const {}

  // Adds force f (world) acting at the world point p to body b (nothing for the ground).
  static void applyForceAt(const VehicleData& data, int body, const Vector3& f_in_world, const Vector3& p_in_world,
                           Eigen::Ref<Eigen::VectorXd> g);
  // Adds a pure moment n (world) to body b (nothing for the ground).
  static void applyMoment(const VehicleData& data, int body, const Vector3& n_in_world, Eigen::Ref<Eigen::VectorXd> g);
  // World position and velocity of the body point s (body frame); for the ground s is the world point.
  static void pointState(const VehicleData& data, int body, const Vector3& s_in_body, Vector3& p_in_world,
                         Vector3& v_in_world);

 private:
  std::string name_;
  int body_i_;
  int body_j_;
};

// Linear spring-damper bushing with per-direction stiffness and damping in a local frame carried by body i
// (suspension element). Deflection d = R^T A_i^T (P_j - P_i) - d0, with R the bushing frame in body i;
// force on body j = A_i R (f0 - K d - C d_dot) with diagonal K, C; body i gets the opposite force at the
// same point (so the pair carries no net moment). Optional rotational stiffness/damping act on the small
// relative rotation of the two bushing frames (rotation vector, body-i bushing axes), e.g. an anti-roll bar.
class Bushing : public ForceElement {
 public:
  struct Parameters {
    Vector3 stiffness = Vector3::Zero();             // K per local axis [N/m]
    Vector3 damping = Vector3::Zero();               // C per local axis [N s/m]
    Vector3 preload = Vector3::Zero();               // f0: force on body j at d = 0, local axes [N]
    Vector3 free_offset = Vector3::Zero();           // d0 [m]
    Vector3 rotational_stiffness = Vector3::Zero();  // [N m/rad] per local axis
    Vector3 rotational_damping = Vector3::Zero();    // [N m s/rad] per local axis
  };
  // s_in_i, s_in_j: attachment points; R_bushing_to_i / _j: bushing frame in each body (equal in the world
  // at the reference configuration, so the relative rotation starts at zero).
  Bushing(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j,
          const Matrix3& R_bushing_to_i, const Matrix3& R_bushing_to_j, const Parameters& parameters);
  void addForces(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> g) const override;
  double potentialEnergy(const VehicleData& data) const override;
  // Deflection d [m] and local force on body j [N] (for tests and output).
  void evaluateLocal(const VehicleData& data, Vector3& deflection, Vector3& force_on_j_local) const;
  const Parameters& parameters() const { return parameters_; }

 private:
  Vector3 s_in_i_, s_in_j_;
  Matrix3 R_bushing_to_i_, R_bushing_to_j_;
  Parameters parameters_;
  bool has_rotational_ = false;
};

// Spring-damper between two points acting along the line joining them (e.g. a yaw damper or a link).
// Tension T = k (L - L0) + c L_dot + f0 pulls the points together.
class PointToPointSpringDamper : public ForceElement {
 public:
  PointToPointSpringDamper(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j,
                           double stiffness, double damping, double free_length, double preload);
  void addForces(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> g) const override;
  double potentialEnergy(const VehicleData& data) const override;

 private:
  Vector3 s_in_i_, s_in_j_;
  double k_, c_, free_length_, preload_;
};

// Bump stop with clearance along one axis of body i (e.g. the lateral bump stop between bogie frame and
// carbody). Deflection d = a . (P_j - P_i) with a the axis in the world; no force while |d| <= clearance,
// beyond it the force sign(d) F(|d|) pushes body j back, F piecewise linear through the table
// (|d| [m], F [N]) that starts at (clearance, 0), extended with the last slope.
class BumpStop : public ForceElement {
 public:
  BumpStop(std::string name, int body_i, int body_j, const Vector3& s_in_i, const Vector3& s_in_j,
           const Vector3& axis_in_i, std::vector<double> deflections, std::vector<double> forces);
  void addForces(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> g) const override;
  double potentialEnergy(const VehicleData& data) const override;
  // Restoring force magnitude [N] at |deflection| x [m].
  double forceAt(double x) const;
  double clearance() const { return deflections_.front(); }

 private:
  double deflection(const VehicleData& data, Vector3& axis_in_world, Vector3& p_j) const;
  Vector3 s_in_i_, s_in_j_, axis_in_i_;
  std::vector<double> deflections_, forces_;
};

}  // namespace rail::vehicle
