// The constant multibody model of a vehicle (the "Model" of the Model/Data split): rigid bodies, joints,
// force elements and named load points, built once and then only read.
//
// Coordinates, per body b of n: q_b = [r (world, m); p (Euler parameters, scalar first)] (7), velocities
// v_b = [r_dot (world, m/s); omega' (body frame, rad/s)] (6). The state vector is y = [q (7n); v (6n)].
// The equations of motion (paper eq. 1) are [M Phi_v^T; Phi_v 0][v_dot; lambda] = [g; gamma - 2 alpha
// Phi_dot - beta^2 Phi], with M = diag(m_b I, J'_b), g the applied forces and Baumgarte terms alpha, beta.
// World frame of the vehicle data: x forward, y to the left, z up.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "rail_vehicle_node/force_element.hpp"
#include "rail_vehicle_node/joint.hpp"
#include "rail_vehicle_node/rigid_math.hpp"

namespace rail::vehicle {

// One rigid body: mass, inertia about its centre of mass and its reference pose.
struct RigidBody {
  std::string name;
  double mass = 0.0;                                  // m [kg]
  Matrix3 inertia_in_body = Matrix3::Identity();      // J' about the centre of mass, body frame [kg m^2]
  Vector3 r_reference = Vector3::Zero();              // centre of mass at the reference configuration [m]
  Vector4 p_reference = Vector4(1.0, 0.0, 0.0, 0.0);  // Euler parameters at the reference configuration
};

// A named body point where the caller applies an external wrench (e.g. a wheel centre).
struct LoadPoint {
  std::string name;
  int body = 0;
  Vector3 s_in_body = Vector3::Zero();  // from the centre of mass, body frame [m]
};

// A named body point whose motion is reported (e.g. an accelerometer on the carbody floor); no force.
struct MeasurementPoint {
  std::string name;
  int body = 0;
  Vector3 s_in_body = Vector3::Zero();    // from the centre of mass, body frame [m]
  Vector3 p_reference = Vector3::Zero();  // the point in the data frame, as the file gives it [m]
};

// How the augmented system is solved: the dense augmented matrix with partial-pivoting LU, or the
// equivalent range-space form (Schur complement Phi_v M^-1 Phi_v^T with LDLT; M^-1 is block diagonal).
enum class KktSolver { kAugmentedLu, kRangeSpace };

// Bodies linked by joints (a connected component of the joint graph, the ground excluded) and the
// constraint rows of their joints. The range-space matrix Phi_v M^-1 Phi_v^T is block diagonal over the
// clusters, so each is factorised on its own (a wheelset and its two axleboxes: 10 rows, not 40).
struct ConstraintCluster {
  std::vector<int> bodies;  // ascending
  std::vector<int> rows;    // constraint rows, ascending
};

class VehicleModel {
 public:
  VehicleModel() = default;
  VehicleModel(VehicleModel&&) = default;
  VehicleModel& operator=(VehicleModel&&) = default;

  // ---- Building (before Finalize) ----
  int addBody(const RigidBody& body);  // returns the body index
  int addLoadPoint(const std::string& name, int body, const Vector3& s_in_body);
  void addJoint(std::unique_ptr<Joint> joint);
  int addMeasurementPointAtWorld(const std::string& name, int body, const Vector3& p_in_world);
  void addForceElement(std::unique_ptr<ForceElement> element);

  // Convenience builders from world-frame data at the reference configuration.
  int addLoadPointAtWorld(const std::string& name, int body, const Vector3& p_in_world);
  void addSphericalJointAt(const std::string& name, int body_i, int body_j, const Vector3& p_in_world);
  void addRevoluteJointAt(const std::string& name, int body_i, int body_j, const Vector3& p_in_world,
                          const Vector3& axis_in_world);
  void addFixedJointAt(const std::string& name, int body_i, int body_j, const Vector3& p_in_world);
  // Bushing at one world point; R_bushing_to_world gives its local axes at the reference configuration.
  void addBushingAt(const std::string& name, int body_i, int body_j, const Vector3& p_in_world,
                    const Matrix3& R_bushing_to_world, const Bushing::Parameters& parameters);
  // Point-to-point element; free_length < 0 takes the reference distance.
  void addPointToPointAt(const std::string& name, int body_i, int body_j, const Vector3& p_i_in_world,
                         const Vector3& p_j_in_world, double stiffness, double damping, double free_length,
                         double preload);
  void addBumpStopAt(const std::string& name, int body_i, int body_j, const Vector3& p_in_world,
                     const Vector3& axis_in_world, std::vector<double> deflections, std::vector<double> forces);

  void setGravity(const Vector3& gravity_in_world);  // [m/s^2], default (0, 0, -9.81)
  void setBaumgarte(double alpha, double beta);      // [1/s], default 10, 10
  void setKktSolver(KktSolver solver);               // default kRangeSpace

  // Checks the model and fixes its sizes; no change is accepted afterwards.
  void finalize();
  bool finalized() const { return finalized_; }

  // ---- Reading ----
  int nBodies() const { return static_cast<int>(bodies_.size()); }
  int nConstraints() const { return n_constraints_; }
  int nPositions() const { return 7 * nBodies(); }
  int nVelocities() const { return 6 * nBodies(); }
  int stateSize() const { return 13 * nBodies(); }
  const std::vector<RigidBody>& bodies() const { return bodies_; }
  const std::vector<LoadPoint>& loadPoints() const { return load_points_; }
  // First to last load point (wheel centre) along the world x axis at the reference configuration [m]: the
  // length the track side sizes its window by (sent in the co-simulation handshake). 0 without load points.
  double wheelSpan() const;
  const std::vector<MeasurementPoint>& measurementPoints() const { return measurement_points_; }
  const std::vector<std::unique_ptr<Joint>>& joints() const { return joints_; }
  const std::vector<std::unique_ptr<ForceElement>>& forceElements() const { return forces_; }
  const std::vector<int>& jointRows() const { return joint_rows_; }  // first constraint row per joint
  const std::vector<ConstraintCluster>& constraintClusters() const { return clusters_; }
  // Cluster index of each body, -1 for a body without joints.
  const std::vector<int>& clusterOfBody() const { return cluster_of_body_; }
  const Vector3& gravity() const { return gravity_; }
  double baumgarteAlpha() const { return alpha_; }
  double baumgarteBeta() const { return beta_; }
  KktSolver kktSolver() const { return kkt_solver_; }
  const Matrix3& inverseInertia(int body) const { return inverse_inertia_[static_cast<std::size_t>(body)]; }
  double totalMass() const;

  // Index lookups by name (building/setup time only; throw std::runtime_error naming the missing name).
  // bodyIndex("ground") is kGround unless a body has that name.
  int bodyIndex(const std::string& name) const;
  int loadPointIndex(const std::string& name) const;

  // State vector offsets of body b.
  static int positionOffset(int b) { return 7 * b; }
  static int eulerOffset(int b) { return 7 * b + 3; }
  int velocityOffset(int b) const { return 7 * nBodies() + 6 * b; }
  int angularVelocityOffset(int b) const { return 7 * nBodies() + 6 * b + 3; }

  // State at the reference configuration, at rest.
  Eigen::VectorXd referenceState() const;

  // A point given in the world at the reference configuration, in the body frame (ground: unchanged).
  Vector3 worldToBodyAtReference(int body, const Vector3& p_in_world) const;
  Matrix3 referenceRotation(int body) const;  // body -> world at the reference (ground: identity)

 private:
  void requireBuilding(const char* what) const;
  void requireBody(int body, bool ground_allowed, const std::string& what) const;

  std::vector<RigidBody> bodies_;
  std::vector<LoadPoint> load_points_;
  std::vector<MeasurementPoint> measurement_points_;
  std::vector<std::unique_ptr<Joint>> joints_;
  std::vector<std::unique_ptr<ForceElement>> forces_;
  std::vector<int> joint_rows_;
  std::vector<ConstraintCluster> clusters_;
  std::vector<int> cluster_of_body_;
  std::vector<Matrix3> inverse_inertia_;
  Vector3 gravity_ = Vector3(0.0, 0.0, -9.81);
  double alpha_ = 10.0;
  double beta_ = 10.0;
  KktSolver kkt_solver_ = KktSolver::kRangeSpace;
  int n_constraints_ = 0;
  bool finalized_ = false;
};

}  // namespace rail::vehicle
