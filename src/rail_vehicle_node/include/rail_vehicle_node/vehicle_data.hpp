// Per-step work state of a vehicle model (the "Data" of the Model/Data split).
//
// Sized once from a finalised VehicleModel and owned by the caller; the right-hand side, the constraint
// evaluation and the projection only write into these preallocated members.
#pragma once

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/LU>
#include <vector>

#include "rail_vehicle_node/rigid_math.hpp"

namespace rail::vehicle {

class VehicleModel;

// World-frame kinematics of one body, evaluated from the state vector.
struct BodyKinematics {
  Vector3 r = Vector3::Zero();            // position of the centre of mass in the world [m]
  Matrix3 A = Matrix3::Identity();        // rotation body -> world
  Vector3 r_dot = Vector3::Zero();        // velocity of the centre of mass in the world [m/s]
  Vector3 omega_body = Vector3::Zero();   // angular velocity in the body frame omega' [rad/s]
  Vector3 omega_world = Vector3::Zero();  // A * omega' [rad/s]
};

// External wrench at one of the model's load points (e.g. a wheel centre), set by the caller.
struct ExternalWrench {
  Vector3 force_in_world = Vector3::Zero();   // [N]
  Vector3 moment_in_world = Vector3::Zero();  // [N m], about the load point
};

// Range-space scratch of one constraint cluster K (VehicleModel::constraintClusters): its rows of Phi_v
// restricted to its bodies' columns (Phi_K), Phi_K M_K^-1, the Schur complement S_K = Phi_K M_K^-1 Phi_K^T
// and its factorisation.
struct ClusterWork {
  explicit ClusterWork(int rows, int n_bodies)
      : phi_v(Eigen::MatrixXd::Zero(rows, 6 * n_bodies)),
        phi_v_m_inv(Eigen::MatrixXd::Zero(rows, 6 * n_bodies)),
        schur(Eigen::MatrixXd::Zero(rows, rows)),
        rhs(Eigen::VectorXd::Zero(rows)),
        mu(Eigen::VectorXd::Zero(rows)),
        top(Eigen::VectorXd::Zero(6 * n_bodies)),
        ldlt(rows) {}
  Eigen::MatrixXd phi_v, phi_v_m_inv, schur;
  Eigen::VectorXd rhs, mu, top;
  Eigen::LDLT<Eigen::MatrixXd> ldlt;
};

class VehicleData {
 public:
  explicit VehicleData(const VehicleModel& model);

  int n_bodies = 0;       // n
  int n_velocities = 0;   // 6 n
  int n_constraints = 0;  // m
  double time = 0.0;      // time of the last right-hand side evaluation [s] (readable by force elements)

  std::vector<BodyKinematics> bodies;    // per body
  std::vector<ExternalWrench> external;  // per load point, set by the caller, held between calls

  Eigen::VectorXd generalized_forces;  // g (6n): per body [f in world; n' in body frame]
  Eigen::VectorXd phi;                 // constraint values Phi (m)
  Eigen::MatrixXd phi_v;               // Jacobian of Phi w.r.t. the velocities [r_dot; omega'] (m x 6n)
  Eigen::VectorXd gamma;               // acceleration right-hand side gamma (m)
  Eigen::VectorXd phi_dot;             // Phi_v * v (m)
  Eigen::VectorXd rhs_c;               // gamma - 2 alpha Phi_dot - beta^2 Phi (m)
  Eigen::VectorXd v_dot;               // accelerations [r_ddot; omega'_dot] (6n)
  Eigen::VectorXd lambda;              // Lagrange multipliers (m)

  // Augmented (KKT) solve: [M Phi_v^T; Phi_v 0].
  Eigen::MatrixXd kkt;
  Eigen::VectorXd kkt_rhs, kkt_sol;
  Eigen::PartialPivLU<Eigen::MatrixXd> kkt_lu;

  // Range-space solve, one constraint cluster at a time.
  Eigen::VectorXd mass_times_x;       // M x = top - Phi_v^T mu of the solve (6n)
  std::vector<ClusterWork> clusters;  // per constraint cluster
  // The range-space solve keeps the clusters' factors of its last call instead of forming them from
  // phi_v (the Jacobian's velocity columns: the positions, hence Phi_v, are those of the last call).
  bool reuse_cluster_factors = false;

  // Scratch for the projection.
  Eigen::VectorXd dx;      // (6n)
  Eigen::VectorXd zero6n;  // (6n), always zero
};

}  // namespace rail::vehicle
