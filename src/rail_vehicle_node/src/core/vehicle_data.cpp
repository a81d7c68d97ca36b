#include "rail_vehicle_node/vehicle_data.hpp"

#include <stdexcept>

#include "rail_vehicle_node/vehicle_model.hpp"

namespace rail::vehicle {

VehicleData::VehicleData(const VehicleModel& model)
    // Factorisations sized in place (a copy of a fresh LDLT would read its uninitialised status field).
    : kkt_lu(model.nVelocities() + model.nConstraints()) {
  if (!model.finalized()) throw std::runtime_error("vehicle data: the model must be finalised first");
  n_bodies = model.nBodies();
  n_velocities = model.nVelocities();
  n_constraints = model.nConstraints();
  const int nv = n_velocities;
  const int m = n_constraints;
  bodies.assign(static_cast<std::size_t>(n_bodies), BodyKinematics{});
  external.assign(model.loadPoints().size(), ExternalWrench{});
  generalized_forces = Eigen::VectorXd::Zero(nv);
  phi = Eigen::VectorXd::Zero(m);
  phi_v = Eigen::MatrixXd::Zero(m, nv);
  gamma = Eigen::VectorXd::Zero(m);
  phi_dot = Eigen::VectorXd::Zero(m);
  rhs_c = Eigen::VectorXd::Zero(m);
  v_dot = Eigen::VectorXd::Zero(nv);
  lambda = Eigen::VectorXd::Zero(m);

  // The mass-matrix block of the augmented matrix is constant: M = diag(m I, J').
  kkt = Eigen::MatrixXd::Zero(nv + m, nv + m);
  for (int b = 0; b < n_bodies; ++b) {
    const RigidBody& body = model.bodies()[static_cast<std::size_t>(b)];
    kkt.block<3, 3>(6 * b, 6 * b) = body.mass * Matrix3::Identity();
    kkt.block<3, 3>(6 * b + 3, 6 * b + 3) = body.inertia_in_body;
  }
  kkt_rhs = Eigen::VectorXd::Zero(nv + m);
  kkt_sol = Eigen::VectorXd::Zero(nv + m);

  mass_times_x = Eigen::VectorXd::Zero(nv);
  clusters.reserve(model.constraintClusters().size());
  for (const ConstraintCluster& c : model.constraintClusters()) {
    clusters.emplace_back(static_cast<int>(c.rows.size()), static_cast<int>(c.bodies.size()));
  }

  dx = Eigen::VectorXd::Zero(nv);
  zero6n = Eigen::VectorXd::Zero(nv);
}

}  // namespace rail::vehicle
