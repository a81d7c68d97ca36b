#include "rail_vehicle_node/multibody_dynamics.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace rail::vehicle {

void computeKinematics(const VehicleModel& model, const Eigen::Ref<const Eigen::VectorXd>& y, VehicleData& data) {
  const int n = model.nBodies();
  for (int b = 0; b < n; ++b) {
    BodyKinematics& k = data.bodies[static_cast<std::size_t>(b)];
    k.r = y.segment<3>(VehicleModel::positionOffset(b));
    k.A = rotationFromEulerParameters(y.segment<4>(VehicleModel::eulerOffset(b)));
    k.r_dot = y.segment<3>(model.velocityOffset(b));
    k.omega_body = y.segment<3>(model.angularVelocityOffset(b));
    k.omega_world = k.A * k.omega_body;
  }
}

namespace {

// Gravity, gyroscopic terms and the external wrenches at the load points.
void computeBodyForces(const VehicleModel& model, VehicleData& data) {
  const int n = model.nBodies();
  const auto& bodies = model.bodies();
  for (int b = 0; b < n; ++b) {
    const RigidBody& body = bodies[static_cast<std::size_t>(b)];
    const BodyKinematics& k = data.bodies[static_cast<std::size_t>(b)];
    data.generalized_forces.segment<3>(6 * b) = body.mass * model.gravity();
    data.generalized_forces.segment<3>(6 * b + 3) = -k.omega_body.cross(body.inertia_in_body * k.omega_body);
  }
  const auto& points = model.loadPoints();
  for (std::size_t p = 0; p < points.size(); ++p) {
    const LoadPoint& lp = points[p];
    const BodyKinematics& k = data.bodies[static_cast<std::size_t>(lp.body)];
    const Vector3 p_in_world = k.r + k.A * lp.s_in_body;
    ForceElement::applyForceAt(data, lp.body, data.external[p].force_in_world, p_in_world, data.generalized_forces);
    ForceElement::applyMoment(data, lp.body, data.external[p].moment_in_world, data.generalized_forces);
  }
}

}  // namespace

void computeAppliedForces(const VehicleModel& model, VehicleData& data) {
  computeBodyForces(model, data);
  for (const auto& element : model.forceElements()) element->addForces(data, data.generalized_forces);
}

void computeElementForces(const VehicleModel& model, VehicleData& data, Eigen::Ref<Eigen::MatrixXd> element_g) {
  const auto& elements = model.forceElements();
  for (std::size_t e = 0; e < elements.size(); ++e) {
    element_g.col(static_cast<Eigen::Index>(e)).setZero();
    elements[e]->addForces(data, element_g.col(static_cast<Eigen::Index>(e)));
  }
}

void computeConstraints(const VehicleModel& model, VehicleData& data) {
  const auto& joints = model.joints();
  const auto& rows = model.jointRows();
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const int row = rows[j];
    const int size = joints[j]->size();
    joints[j]->evaluate(data, data.phi.segment(row, size), data.phi_v.middleRows(row, size),
                        data.gamma.segment(row, size));
  }
}

namespace {

// phi_dot = Phi_v v from the joints' own blocks (a joint's rows are zero outside its two bodies' columns).
void constraintVelocity(const VehicleModel& model, const Eigen::Ref<const Eigen::VectorXd>& v, VehicleData& data) {
  const auto& joints = model.joints();
  const auto& rows = model.jointRows();
  for (std::size_t j = 0; j < joints.size(); ++j) {
    const int bi = joints[j]->bodyI(), bj = joints[j]->bodyJ();
    for (int r = rows[j]; r < rows[j] + joints[j]->size(); ++r) {
      double sum = 0.0;
      if (bi != kGround) sum += data.phi_v.block<1, 6>(r, 6 * bi).dot(v.segment<6>(6 * bi).transpose());
      if (bj != kGround) sum += data.phi_v.block<1, 6>(r, 6 * bj).dot(v.segment<6>(6 * bj).transpose());
      data.phi_dot[r] = sum;
    }
  }
}

// x = M^-1 rhs with M = diag(m I, J') per body.
void applyInverseMass(const VehicleModel& model, const Eigen::Ref<const Eigen::VectorXd>& rhs,
                      Eigen::Ref<Eigen::VectorXd> x) {
  const auto& bodies = model.bodies();
  for (int b = 0; b < model.nBodies(); ++b) {
    x.segment<3>(6 * b) = rhs.segment<3>(6 * b) / bodies[static_cast<std::size_t>(b)].mass;
    x.segment<3>(6 * b + 3) = model.inverseInertia(b) * rhs.segment<3>(6 * b + 3);
  }
}

}  // namespace

void solveAugmented(const VehicleModel& model, VehicleData& data, const Eigen::Ref<const Eigen::VectorXd>& top,
                    const Eigen::Ref<const Eigen::VectorXd>& bottom, Eigen::Ref<Eigen::VectorXd> x,
                    Eigen::Ref<Eigen::VectorXd> mu) {
  const int nv = model.nVelocities();
  const int m = model.nConstraints();
  if (m == 0) {
    applyInverseMass(model, top, x);
    return;
  }
  if (model.kktSolver() == KktSolver::kAugmentedLu) {
    data.kkt.bottomLeftCorner(m, nv) = data.phi_v;
    data.kkt.topRightCorner(nv, m) = data.phi_v.transpose();
    data.kkt_lu.compute(data.kkt);
    data.kkt_rhs.head(nv) = top;
    data.kkt_rhs.tail(m) = bottom;
    data.kkt_sol = data.kkt_lu.solve(data.kkt_rhs);
    x = data.kkt_sol.head(nv);
    mu = data.kkt_sol.tail(m);
    return;
  }
  // Range space, one joint cluster at a time (S is block diagonal over them): for cluster K,
  // (Phi_K M_K^-1 Phi_K^T) mu_K = Phi_K M_K^-1 top_K - bottom_K; x = M^-1 (top - Phi_v^T mu).
  const auto& bodies = model.bodies();
  const auto& clusters = model.constraintClusters();
  data.mass_times_x = top;
  for (std::size_t c = 0; c < clusters.size(); ++c) {
    const ConstraintCluster& cluster = clusters[c];
    ClusterWork& cw = data.clusters[c];
    const int n_rows = static_cast<int>(cluster.rows.size());
    for (std::size_t k = 0; k < cluster.bodies.size(); ++k) {
      const int b = cluster.bodies[k];
      const int col = 6 * static_cast<int>(k);
      cw.top.segment<6>(col) = top.segment<6>(6 * b);
      if (data.reuse_cluster_factors) continue;
      for (int i = 0; i < n_rows; ++i) {
        cw.phi_v.block<1, 6>(i, col) = data.phi_v.block<1, 6>(cluster.rows[static_cast<std::size_t>(i)], 6 * b);
      }
      cw.phi_v_m_inv.middleCols<3>(col) = cw.phi_v.middleCols<3>(col) / bodies[static_cast<std::size_t>(b)].mass;
      cw.phi_v_m_inv.middleCols<3>(col + 3).noalias() = cw.phi_v.middleCols<3>(col + 3) * model.inverseInertia(b);
    }
    // Blocks of ~10 x 18: coefficient-wise (lazy) products, not the general matrix-product kernel.
    if (!data.reuse_cluster_factors) {
      cw.schur.noalias() = cw.phi_v_m_inv.lazyProduct(cw.phi_v.transpose());
      cw.ldlt.compute(cw.schur);
    }
    cw.rhs.noalias() = cw.phi_v_m_inv.lazyProduct(cw.top);
    for (int i = 0; i < n_rows; ++i) cw.rhs[i] -= bottom[cluster.rows[static_cast<std::size_t>(i)]];
    cw.mu = cw.ldlt.solve(cw.rhs);
    for (int i = 0; i < n_rows; ++i) mu[cluster.rows[static_cast<std::size_t>(i)]] = cw.mu[i];
    cw.top.noalias() -= cw.phi_v.transpose().lazyProduct(cw.mu);
    for (std::size_t k = 0; k < cluster.bodies.size(); ++k) {
      data.mass_times_x.segment<6>(6 * cluster.bodies[k]) = cw.top.segment<6>(6 * static_cast<int>(k));
    }
  }
  applyInverseMass(model, data.mass_times_x, x);
}

namespace {

// q_dot from v (p_dot = 1/2 p (x) (0, omega')), after the kinematics.
void positionDerivatives(const VehicleModel& model, const Eigen::Ref<const Eigen::VectorXd>& y,
                         Eigen::Ref<Eigen::VectorXd> y_dot, const VehicleData& data) {
  const int n = model.nBodies();
  for (int b = 0; b < n; ++b) {
    const BodyKinematics& k = data.bodies[static_cast<std::size_t>(b)];
    y_dot.segment<3>(VehicleModel::positionOffset(b)) = k.r_dot;
    // p_dot = 1/2 p (x) (0, omega'), with the raw (unnormalised) p so that d|p|^2/dt = 0 exactly.
    const Vector4 p = y.segment<4>(VehicleModel::eulerOffset(b));
    Vector4 p_dot;
    p_dot[0] = -0.5 * p.tail<3>().dot(k.omega_body);
    p_dot.tail<3>() = 0.5 * (p[0] * k.omega_body + p.tail<3>().cross(k.omega_body));
    y_dot.segment<4>(VehicleModel::eulerOffset(b)) = p_dot;
  }
}

// v_dot and lambda from the Baumgarte-stabilised augmented system, after data.generalized_forces.
void velocityDerivatives(const VehicleModel& model, const Eigen::Ref<const Eigen::VectorXd>& y,
                         Eigen::Ref<Eigen::VectorXd> y_dot, VehicleData& data) {
  const int m = model.nConstraints();
  if (m > 0) {
    computeConstraints(model, data);
    constraintVelocity(model, y.tail(model.nVelocities()), data);
    const double alpha = model.baumgarteAlpha();
    const double beta = model.baumgarteBeta();
    data.rhs_c = data.gamma - 2.0 * alpha * data.phi_dot - (beta * beta) * data.phi;
  }
  solveAugmented(model, data, data.generalized_forces, data.rhs_c, data.v_dot, data.lambda);
  y_dot.tail(model.nVelocities()) = data.v_dot;
}

}  // namespace

void computeDerivatives(const VehicleModel& model, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                        Eigen::Ref<Eigen::VectorXd> y_dot, VehicleData& data) {
  data.time = t;
  computeKinematics(model, y, data);
  positionDerivatives(model, y, y_dot, data);
  computeAppliedForces(model, data);
  velocityDerivatives(model, y, y_dot, data);
}

void computeDerivativesPartial(const VehicleModel& model, double t, const Eigen::Ref<const Eigen::VectorXd>& y,
                               Eigen::Ref<Eigen::VectorXd> y_dot, VehicleData& data, const std::vector<char>& live,
                               const Eigen::Ref<const Eigen::MatrixXd>& element_g) {
  data.time = t;
  computeKinematics(model, y, data);
  positionDerivatives(model, y, y_dot, data);
  computeBodyForces(model, data);
  const auto& elements = model.forceElements();
  for (std::size_t e = 0; e < elements.size(); ++e) {
    if (live[e] != 0) {
      elements[e]->addForces(data, data.generalized_forces);
    } else {
      data.generalized_forces += element_g.col(static_cast<Eigen::Index>(e));
    }
  }
  velocityDerivatives(model, y, y_dot, data);
}

ConstraintViolation evaluateViolation(const VehicleModel& model, const Eigen::Ref<const Eigen::VectorXd>& y,
                                      VehicleData& data) {
  ConstraintViolation v;
  for (int b = 0; b < model.nBodies(); ++b) {
    v.euler_norm = std::max(v.euler_norm, std::abs(y.segment<4>(VehicleModel::eulerOffset(b)).norm() - 1.0));
  }
  if (model.nConstraints() == 0) return v;
  computeKinematics(model, y, data);
  computeConstraints(model, data);
  constraintVelocity(model, y.tail(model.nVelocities()), data);
  v.position = data.phi.lpNorm<Eigen::Infinity>();
  v.velocity = data.phi_dot.lpNorm<Eigen::Infinity>();
  return v;
}

int projectState(const VehicleModel& model, Eigen::Ref<Eigen::VectorXd> y, VehicleData& data, double tolerance,
                 int max_iterations) {
  const int n = model.nBodies();
  for (int b = 0; b < n; ++b) y.segment<4>(VehicleModel::eulerOffset(b)).normalize();
  if (model.nConstraints() == 0) return 0;
  int iterations = 0;
  for (;;) {
    computeKinematics(model, y, data);
    computeConstraints(model, data);
    const double violation = data.phi.lpNorm<Eigen::Infinity>();
    if (violation <= tolerance) break;
    if (iterations >= max_iterations || !std::isfinite(violation)) {
      std::ostringstream os;
      os << "constraint projection: max |Phi| = " << violation << " after " << iterations << " iterations, tolerance "
         << tolerance;
      throw std::runtime_error(os.str());
    }
    data.rhs_c = -data.phi;
    solveAugmented(model, data, data.zero6n, data.rhs_c, data.dx, data.lambda);
    for (int b = 0; b < n; ++b) {
      y.segment<3>(VehicleModel::positionOffset(b)) += data.dx.segment<3>(6 * b);
      const Vector4 p = y.segment<4>(VehicleModel::eulerOffset(b));
      y.segment<4>(VehicleModel::eulerOffset(b)) =
          quaternionProduct(p, eulerParametersFromRotationVector(data.dx.segment<3>(6 * b + 3))).normalized();
    }
    ++iterations;
  }
  // Velocities: v <- v + dv with [M Phi_v^T; Phi_v 0][dv; mu] = [0; -Phi_v v] (kinetic-energy metric).
  constraintVelocity(model, y.tail(model.nVelocities()), data);
  data.rhs_c = -data.phi_dot;
  solveAugmented(model, data, data.zero6n, data.rhs_c, data.dx, data.lambda);
  y.tail(model.nVelocities()) += data.dx;
  return iterations;
}

double kineticEnergy(const VehicleModel& model, const VehicleData& data) {
  double energy = 0.0;
  for (int b = 0; b < model.nBodies(); ++b) {
    const RigidBody& body = model.bodies()[static_cast<std::size_t>(b)];
    const BodyKinematics& k = data.bodies[static_cast<std::size_t>(b)];
    energy += 0.5 * body.mass * k.r_dot.squaredNorm() + 0.5 * k.omega_body.dot(body.inertia_in_body * k.omega_body);
  }
  return energy;
}

double potentialEnergy(const VehicleModel& model, const VehicleData& data) {
  double energy = 0.0;
  for (int b = 0; b < model.nBodies(); ++b) {
    energy -= model.bodies()[static_cast<std::size_t>(b)].mass *
              model.gravity().dot(data.bodies[static_cast<std::size_t>(b)].r);
  }
  for (const auto& element : model.forceElements()) energy += element->potentialEnergy(data);
  return energy;
}

Vector3 linearMomentum(const VehicleModel& model, const VehicleData& data) {
  Vector3 l = Vector3::Zero();
  for (int b = 0; b < model.nBodies(); ++b) {
    l += model.bodies()[static_cast<std::size_t>(b)].mass * data.bodies[static_cast<std::size_t>(b)].r_dot;
  }
  return l;
}

Vector3 angularMomentum(const VehicleModel& model, const VehicleData& data) {
  Vector3 h = Vector3::Zero();
  for (int b = 0; b < model.nBodies(); ++b) {
    const RigidBody& body = model.bodies()[static_cast<std::size_t>(b)];
    const BodyKinematics& k = data.bodies[static_cast<std::size_t>(b)];
    h += k.r.cross(body.mass * k.r_dot) + k.A * (body.inertia_in_body * k.omega_body);
  }
  return h;
}

void loadPointState(const VehicleModel& model, const VehicleData& data, int k, Vector3& p_in_world,
                    Vector3& v_in_world) {
  const LoadPoint& lp = model.loadPoints()[static_cast<std::size_t>(k)];
  ForceElement::pointState(data, lp.body, lp.s_in_body, p_in_world, v_in_world);
}

}  // namespace rail::vehicle
