#include "rail_vehicle_node/vehicle_model.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace rail::vehicle {

void VehicleModel::requireBuilding(const char* what) const {
  if (finalized_) throw std::runtime_error(std::string("vehicle model: ") + what + " after Finalize()");
}

void VehicleModel::requireBody(int body, bool ground_allowed, const std::string& what) const {
  if ((ground_allowed && body == kGround) || (body >= 0 && body < nBodies())) return;
  throw std::runtime_error("vehicle model: " + what + ": body index " + std::to_string(body) + " out of range (" +
                           std::to_string(nBodies()) + " bodies)");
}

int VehicleModel::addBody(const RigidBody& body) {
  requireBuilding("AddBody");
  std::ostringstream os;
  if (!(body.mass > 0.0) || !std::isfinite(body.mass)) {
    os << "vehicle model: body " << body.name << ": mass must be > 0, got " << body.mass;
    throw std::runtime_error(os.str());
  }
  const Matrix3 J = body.inertia_in_body;
  if (!J.allFinite() || (J - J.transpose()).norm() > 1e-9 * J.norm()) {
    os << "vehicle model: body " << body.name << ": inertia must be finite and symmetric";
    throw std::runtime_error(os.str());
  }
  const Eigen::Vector3d eig = Eigen::SelfAdjointEigenSolver<Matrix3>(J).eigenvalues();
  if (!(eig.minCoeff() > 0.0)) {
    os << "vehicle model: body " << body.name << ": inertia must be positive definite, smallest eigenvalue "
       << eig.minCoeff();
    throw std::runtime_error(os.str());
  }
  if (!body.r_reference.allFinite() || !(body.p_reference.norm() > 0.0)) {
    os << "vehicle model: body " << body.name << ": reference pose not finite";
    throw std::runtime_error(os.str());
  }
  for (const auto& b : bodies_) {
    if (b.name == body.name) throw std::runtime_error("vehicle model: body name " + body.name + " defined twice");
  }
  RigidBody stored = body;
  stored.p_reference.normalize();
  bodies_.push_back(stored);
  inverse_inertia_.push_back(J.inverse());
  return nBodies() - 1;
}

int VehicleModel::addLoadPoint(const std::string& name, int body, const Vector3& s_in_body) {
  requireBuilding("AddLoadPoint");
  requireBody(body, false, "load point " + name);
  for (const auto& p : load_points_) {
    if (p.name == name) throw std::runtime_error("vehicle model: load point name " + name + " defined twice");
  }
  load_points_.push_back(LoadPoint{name, body, s_in_body});
  return static_cast<int>(load_points_.size()) - 1;
}

void VehicleModel::addJoint(std::unique_ptr<Joint> joint) {
  requireBuilding("AddJoint");
  requireBody(joint->bodyI(), false, "joint " + joint->name() + " body_i");
  requireBody(joint->bodyJ(), true, "joint " + joint->name() + " body_j");
  if (joint->bodyI() == joint->bodyJ()) {
    throw std::runtime_error("vehicle model: joint " + joint->name() + " connects a body to itself");
  }
  joints_.push_back(std::move(joint));
}

void VehicleModel::addForceElement(std::unique_ptr<ForceElement> element) {
  requireBuilding("AddForceElement");
  requireBody(element->bodyI(), true, "force element " + element->name() + " body_i");
  requireBody(element->bodyJ(), true, "force element " + element->name() + " body_j");
  forces_.push_back(std::move(element));
}

Matrix3 VehicleModel::referenceRotation(int body) const {
  if (body == kGround) return Matrix3::Identity();
  requireBody(body, false, "reference rotation");
  return rotationFromEulerParameters(bodies_[static_cast<std::size_t>(body)].p_reference);
}

Vector3 VehicleModel::worldToBodyAtReference(int body, const Vector3& p_in_world) const {
  if (body == kGround) return p_in_world;
  requireBody(body, false, "world to body");
  return referenceRotation(body).transpose() * (p_in_world - bodies_[static_cast<std::size_t>(body)].r_reference);
}

double VehicleModel::wheelSpan() const {
  if (load_points_.empty()) return 0.0;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const LoadPoint& p : load_points_) {
    const double x =
        p.body == kGround
            ? p.s_in_body.x()
            : (bodies_[static_cast<std::size_t>(p.body)].r_reference + referenceRotation(p.body) * p.s_in_body).x();
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  return hi - lo;
}

int VehicleModel::addMeasurementPointAtWorld(const std::string& name, int body, const Vector3& p_in_world) {
  requireBuilding("AddMeasurementPointAtWorld");
  requireBody(body, false, "measurement point " + name);
  for (const auto& p : measurement_points_) {
    if (p.name == name) throw std::runtime_error("measurement point '" + name + "' defined twice");
  }
  measurement_points_.push_back(MeasurementPoint{name, body, worldToBodyAtReference(body, p_in_world), p_in_world});
  return static_cast<int>(measurement_points_.size()) - 1;
}

int VehicleModel::addLoadPointAtWorld(const std::string& name, int body, const Vector3& p_in_world) {
  requireBody(body, false, "load point " + name);
  return addLoadPoint(name, body, worldToBodyAtReference(body, p_in_world));
}

void VehicleModel::addSphericalJointAt(const std::string& name, int body_i, int body_j, const Vector3& p_in_world) {
  requireBody(body_i, false, "joint " + name + " body_i");
  requireBody(body_j, true, "joint " + name + " body_j");
  addJoint(std::make_unique<SphericalJoint>(name, body_i, body_j, worldToBodyAtReference(body_i, p_in_world),
                                            worldToBodyAtReference(body_j, p_in_world)));
}

void VehicleModel::addRevoluteJointAt(const std::string& name, int body_i, int body_j, const Vector3& p_in_world,
                                      const Vector3& axis_in_world) {
  requireBody(body_i, false, "joint " + name + " body_i");
  requireBody(body_j, true, "joint " + name + " body_j");
  addJoint(std::make_unique<RevoluteJoint>(
      name, body_i, body_j, worldToBodyAtReference(body_i, p_in_world), worldToBodyAtReference(body_j, p_in_world),
      referenceRotation(body_i).transpose() * axis_in_world, referenceRotation(body_j).transpose() * axis_in_world));
}

void VehicleModel::addFixedJointAt(const std::string& name, int body_i, int body_j, const Vector3& p_in_world) {
  requireBody(body_i, false, "joint " + name + " body_i");
  requireBody(body_j, true, "joint " + name + " body_j");
  addJoint(std::make_unique<FixedJoint>(name, body_i, body_j, worldToBodyAtReference(body_i, p_in_world),
                                        worldToBodyAtReference(body_j, p_in_world),
                                        referenceRotation(body_i).transpose(), referenceRotation(body_j).transpose()));
}

void VehicleModel::addBushingAt(const std::string& name, int body_i, int body_j, const Vector3& p_in_world,
                                const Matrix3& R_bushing_to_world, const Bushing::Parameters& parameters) {
  requireBody(body_i, true, "bushing " + name + " body_i");
  requireBody(body_j, true, "bushing " + name + " body_j");
  addForceElement(std::make_unique<Bushing>(name, body_i, body_j, worldToBodyAtReference(body_i, p_in_world),
                                            worldToBodyAtReference(body_j, p_in_world),
                                            referenceRotation(body_i).transpose() * R_bushing_to_world,
                                            referenceRotation(body_j).transpose() * R_bushing_to_world, parameters));
}

void VehicleModel::addPointToPointAt(const std::string& name, int body_i, int body_j, const Vector3& p_i_in_world,
                                     const Vector3& p_j_in_world, double stiffness, double damping, double free_length,
                                     double preload) {
  requireBody(body_i, true, "point-to-point " + name + " body_i");
  requireBody(body_j, true, "point-to-point " + name + " body_j");
  const double length = free_length < 0.0 ? (p_j_in_world - p_i_in_world).norm() : free_length;
  addForceElement(std::make_unique<PointToPointSpringDamper>(
      name, body_i, body_j, worldToBodyAtReference(body_i, p_i_in_world), worldToBodyAtReference(body_j, p_j_in_world),
      stiffness, damping, length, preload));
}

void VehicleModel::addBumpStopAt(const std::string& name, int body_i, int body_j, const Vector3& p_in_world,
                                 const Vector3& axis_in_world, std::vector<double> deflections,
                                 std::vector<double> forces) {
  requireBody(body_i, true, "bump stop " + name + " body_i");
  requireBody(body_j, true, "bump stop " + name + " body_j");
  addForceElement(std::make_unique<BumpStop>(
      name, body_i, body_j, worldToBodyAtReference(body_i, p_in_world), worldToBodyAtReference(body_j, p_in_world),
      referenceRotation(body_i).transpose() * axis_in_world, std::move(deflections), std::move(forces)));
}

void VehicleModel::setGravity(const Vector3& gravity_in_world) {
  requireBuilding("SetGravity");
  if (!gravity_in_world.allFinite()) throw std::runtime_error("vehicle model: gravity not finite");
  gravity_ = gravity_in_world;
}

void VehicleModel::setBaumgarte(double alpha, double beta) {
  requireBuilding("SetBaumgarte");
  if (!(alpha >= 0.0) || !(beta >= 0.0) || !std::isfinite(alpha) || !std::isfinite(beta)) {
    std::ostringstream os;
    os << "vehicle model: Baumgarte alpha and beta must be finite and >= 0, got " << alpha << ", " << beta;
    throw std::runtime_error(os.str());
  }
  alpha_ = alpha;
  beta_ = beta;
}

void VehicleModel::setKktSolver(KktSolver solver) {
  requireBuilding("SetKktSolver");
  kkt_solver_ = solver;
}

void VehicleModel::finalize() {
  requireBuilding("Finalize");
  if (bodies_.empty()) throw std::runtime_error("vehicle model: no bodies");
  joint_rows_.clear();
  n_constraints_ = 0;
  for (const auto& j : joints_) {
    joint_rows_.push_back(n_constraints_);
    n_constraints_ += j->size();
  }
  // Joint clusters: connected components of the bodies over the joints (union-find).
  const int n = nBodies();
  std::vector<int> parent(static_cast<std::size_t>(n));
  for (int b = 0; b < n; ++b) parent[static_cast<std::size_t>(b)] = b;
  const auto root = [&parent](int b) {
    while (parent[static_cast<std::size_t>(b)] != b) b = parent[static_cast<std::size_t>(b)];
    return b;
  };
  for (const auto& j : joints_) {
    if (j->bodyI() != kGround && j->bodyJ() != kGround)
      parent[static_cast<std::size_t>(root(j->bodyI()))] = root(j->bodyJ());
  }
  clusters_.clear();
  cluster_of_body_.assign(static_cast<std::size_t>(n), -1);
  std::vector<int> cluster_of_root(static_cast<std::size_t>(n), -1);
  for (std::size_t k = 0; k < joints_.size(); ++k) {
    const int b = joints_[k]->bodyI() != kGround ? joints_[k]->bodyI() : joints_[k]->bodyJ();
    if (b == kGround) continue;
    int& c = cluster_of_root[static_cast<std::size_t>(root(b))];
    if (c < 0) {
      c = static_cast<int>(clusters_.size());
      clusters_.emplace_back();
    }
    for (int r = 0; r < joints_[k]->size(); ++r)
      clusters_[static_cast<std::size_t>(c)].rows.push_back(joint_rows_[k] + r);
  }
  for (int b = 0; b < n; ++b) {
    const int c = cluster_of_root[static_cast<std::size_t>(root(b))];
    if (c < 0) continue;
    cluster_of_body_[static_cast<std::size_t>(b)] = c;
    clusters_[static_cast<std::size_t>(c)].bodies.push_back(b);
  }
  finalized_ = true;
}

double VehicleModel::totalMass() const {
  double m = 0.0;
  for (const auto& b : bodies_) m += b.mass;
  return m;
}

int VehicleModel::bodyIndex(const std::string& name) const {
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    if (bodies_[k].name == name) return static_cast<int>(k);
  }
  if (name == "ground") return kGround;
  throw std::runtime_error("vehicle model: no body named " + name);
}

int VehicleModel::loadPointIndex(const std::string& name) const {
  for (std::size_t k = 0; k < load_points_.size(); ++k) {
    if (load_points_[k].name == name) return static_cast<int>(k);
  }
  throw std::runtime_error("vehicle model: no load point named " + name);
}

Eigen::VectorXd VehicleModel::referenceState() const {
  Eigen::VectorXd y = Eigen::VectorXd::Zero(stateSize());
  for (int b = 0; b < nBodies(); ++b) {
    y.segment<3>(positionOffset(b)) = bodies_[static_cast<std::size_t>(b)].r_reference;
    y.segment<4>(eulerOffset(b)) = bodies_[static_cast<std::size_t>(b)].p_reference;
  }
  return y;
}

}  // namespace rail::vehicle
