// Forward dynamics of a VehicleModel: kinematics, applied forces g, constraints (Phi, Phi_v, gamma), the
// augmented-system solve for accelerations and Lagrange multipliers, constraint violation and projection.
//
// All functions write only into the caller's VehicleData (preallocated): no allocation on these paths.
// y is the state [q (7n); v (6n)] described in vehicle_model.hpp.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "rail_vehicle_node/vehicle_data.hpp"
#include "rail_vehicle_node/vehicle_model.hpp"

namespace rail::vehicle {

// Body kinematics (positions, rotations, velocities) from y into data.bodies.
void computeKinematics(const VehicleModel& model, const Eigen::Ref<const Eigen::VectorXd>& y, VehicleData& data);

// g: gravity, gyroscopic terms -omega' x J' omega', force elements and external wrenches (after kinematics).
void computeAppliedForces(const VehicleModel& model, VehicleData& data);

// Phi, Phi_v and gamma of all joints (after kinematics).
void computeConstraints(const VehicleModel& model, VehicleData& data);

// Solves [M Phi_v^T; Phi_v 0][x; mu] = [top; bottom] with the model's KktSolver, using data.phi_v.
// top/bottom must not alias the solver's scratch (data.kkt_*, data.mass_times_x, data.clusters).
void solveAugmented(const VehicleModel& model, VehicleData& data, const Eigen::Ref<const Eigen::VectorXd>& top,
                    const Eigen::Ref<const Eigen::VectorXd>& bottom, Eigen::Ref<Eigen::VectorXd> x,
                    Eigen::Ref<Eigen::VectorXd> mu);

// Right-hand side y_dot = f(t, y): q_dot from v (p_dot = 1/2 p (x) (0, omega')), v_dot and lambda from the
// Baumgarte-stabilised augmented system. Leaves data.v_dot, data.lambda, data.phi, ... filled in.
void computeDerivatives(const VehicleModel& model, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                        Eigen::Ref<Eigen::VectorXd> y_dot, VehicleData& data);

// Each force element's contribution to g at the current kinematics, one column of element_g (6n x
// elements) per element (for the Jacobian's partial evaluations, vehicle_jacobian.hpp).
void computeElementForces(const VehicleModel& model, VehicleData& data, Eigen::Ref<Eigen::MatrixXd> element_g);

// computeDerivatives with the force elements whose live[e] is 0 taken from element_g's column e instead of
// evaluated (the others are evaluated at y as usual).
void computeDerivativesPartial(const VehicleModel& model, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                               Eigen::Ref<Eigen::VectorXd> y_dot, VehicleData& data, const std::vector<char>& live,
                               const Eigen::Ref<const Eigen::MatrixXd>& element_g);

// Constraint violation of a state (infinity norms).
struct ConstraintViolation {
  double position = 0.0;    // max |Phi| [m, or dimensionless for orientation rows]
  double velocity = 0.0;    // max |Phi_v v| [m/s, or 1/s]
  double euler_norm = 0.0;  // max |‖p‖ - 1| over the bodies
};
ConstraintViolation evaluateViolation(const VehicleModel& model, const Eigen::Ref<const Eigen::VectorXd>& y,
                                      VehicleData& data);

// Projects y onto the constraint manifold: Euler parameters normalised, positions corrected by mass-weighted
// minimum-norm Gauss-Newton steps [M Phi_v^T; Phi_v 0][dx; mu] = [0; -Phi] (dx = [dr; dtheta'] with the body
// rotation updated as p <- p (x) exp(dtheta'/2)) until max |Phi| <= tolerance, then velocities by the
// kinetic-energy-metric projection (same system with -Phi_v v). Returns the number of position
// iterations; throws std::runtime_error if the tolerance is not met in max_iterations.
int projectState(const VehicleModel& model, Eigen::Ref<Eigen::VectorXd> y, VehicleData& data, double tolerance,
                 int max_iterations);

// Energies and momenta (after computeKinematics).
double kineticEnergy(const VehicleModel& model, const VehicleData& data);     // [J]
double potentialEnergy(const VehicleModel& model, const VehicleData& data);   // gravity + elements [J]
Vector3 linearMomentum(const VehicleModel& model, const VehicleData& data);   // world [kg m/s]
Vector3 angularMomentum(const VehicleModel& model, const VehicleData& data);  // about the world origin

// World position and velocity of load point k (after computeKinematics), e.g. a wheel centre.
void loadPointState(const VehicleModel& model, const VehicleData& data, int k, Vector3& p_in_world,
                    Vector3& v_in_world);

}  // namespace rail::vehicle
