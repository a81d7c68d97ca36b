#include "rail_contact/rail_deformation.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "rail_contact/beam_shape.hpp"

namespace rail {
namespace contact {

BeamRailDeformation::BeamRailDeformation(double s_start, double element_arc_length,
                                         std::array<std::vector<RailBeamElement>, 2> elements)
    : s_start_(s_start), h_(element_arc_length), elements_(std::move(elements)) {
  if (!(h_ > 0.0) || !std::isfinite(h_) || !std::isfinite(s_start_)) {
    std::ostringstream m;
    m << "BeamRailDeformation: element_arc_length must be positive and finite (" << h_ << " m)";
    throw std::runtime_error(m.str());
  }
  for (int r = 0; r < 2; ++r) {
    if (elements_[r].empty())
      throw std::runtime_error(std::string("BeamRailDeformation: no elements on the ") + (r == 0 ? "left" : "right") +
                               " rail");
    for (std::size_t k = 0; k < elements_[r].size(); ++k) {
      if (!(elements_[r][k].length > 0.0)) {
        std::ostringstream m;
        m << "BeamRailDeformation: element " << k << " of the " << (r == 0 ? "left" : "right")
          << " rail has a non-positive length (" << elements_[r][k].length << " m)";
        throw std::runtime_error(m.str());
      }
    }
    q_[r].assign(6 * (elements_[r].size() + 1), 0.0);
    qdot_[r].assign(6 * (elements_[r].size() + 1), 0.0);
  }
}

void BeamRailDeformation::setZero() {
  for (int r = 0; r < 2; ++r) {
    std::fill(q_[r].begin(), q_[r].end(), 0.0);
    std::fill(qdot_[r].begin(), qdot_[r].end(), 0.0);
  }
}

bool BeamRailDeformation::locate(RailSide side, double s, int& element, double& xi) const noexcept {
  const int n = static_cast<int>(elements_[idx(side)].size());
  const double t = (s - s_start_) / h_;
  if (!(t >= 0.0) || !(t <= n)) return false;
  element = std::min(static_cast<int>(t), n - 1);
  xi = t - element;
  return true;
}

void BeamRailDeformation::sectionMotion(RailSide side, double s, RailSectionMotion& out) const noexcept {
  int e;
  double xi;
  if (!locate(side, s, e, xi)) {
    out.setZero();
    return;
  }
  const int r = idx(side);
  const RailBeamElement& el = elements_[r][e];
  const Eigen::Matrix3d& R = el.R_local_to_world;
  // Nodal DOFs of the element, world axes -> local axes (block-wise R^T).
  Vector12d d_local, v_local;
  const double* q = q_[r].data() + 6 * e;
  const double* v = qdot_[r].data() + 6 * e;
  for (int b = 0; b < 4; ++b) {
    d_local.segment<3>(3 * b) = R.transpose() * Eigen::Map<const Eigen::Vector3d>(q + 3 * b);
    v_local.segment<3>(3 * b) = R.transpose() * Eigen::Map<const Eigen::Vector3d>(v + 3 * b);
  }
  Matrix3x12 N_u, N_theta, dN_u, dN_theta;
  beamShapeDisplacement(xi, el.length, N_u);
  beamShapeRotation(xi, el.length, N_theta);
  beamShapeDisplacementDs(xi, el.length, dN_u);
  beamShapeRotationDs(xi, el.length, dN_theta);
  // d(element coordinate)/d(track arc length): element chord length over its arc-length span.
  const double ds_local_ds = el.length / h_;
  out.u = R * (N_u * d_local);
  out.theta = R * (N_theta * d_local);
  out.du_ds = ds_local_ds * (R * (dN_u * d_local));
  out.dtheta_ds = ds_local_ds * (R * (dN_theta * d_local));
  out.u_dot = R * (N_u * v_local);
  out.theta_dot = R * (N_theta * v_local);
}

Eigen::Matrix3d smallRotationMatrix(const Eigen::Vector3d& theta) noexcept {
  const double a2 = theta.squaredNorm();
  Eigen::Matrix3d K;
  K << 0.0, -theta.z(), theta.y(), theta.z(), 0.0, -theta.x(), -theta.y(), theta.x(), 0.0;
  double c1, c2;  // sin(a)/a and (1 - cos a)/a^2, by series for small a
  if (a2 < 1e-8) {
    c1 = 1.0 - a2 / 6.0;
    c2 = 0.5 - a2 / 24.0;
  } else {
    const double a = std::sqrt(a2);
    c1 = std::sin(a) / a;
    c2 = (1.0 - std::cos(a)) / a2;
  }
  return Eigen::Matrix3d::Identity() + c1 * K + c2 * K * K;
}

}  // namespace contact
}  // namespace rail
