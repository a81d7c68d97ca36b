#include "rail_contact/wheel_defects.hpp"

#include <algorithm>
#include <cmath>

namespace rail::contact {

namespace {

constexpr double kPi = 3.14159265358979323846;

// psi in (-pi, pi].
double wrapAngle(double psi) {
  psi = std::remainder(psi, 2.0 * kPi);
  return psi == -kPi ? kPi : psi;
}

}  // namespace

WheelDefects::WheelDefects(std::vector<WheelDefect> defects, double radius) : radius_(radius) {
  for (const WheelDefect& d : defects) {
    const bool ok = d.shape == WheelDefectShape::kFlat ? d.length > 0.0 && d.length < 2.0 * radius
                                                       : d.order >= 1 && std::isfinite(d.amplitude);
    if (ok && std::isfinite(d.angle)) defects_.push_back(d);
  }
  std::stable_sort(defects_.begin(), defects_.end(),
                   [](const WheelDefect& a, const WheelDefect& b) { return a.wheel < b.wheel; });
  const std::uint32_t wheels = defects_.empty() ? 0 : defects_.back().wheel + 1;
  first_.assign(wheels + 1, 0);
  for (const WheelDefect& d : defects_) ++first_[d.wheel + 1];
  for (std::uint32_t w = 0; w < wheels; ++w) first_[w + 1] += first_[w];
}

double WheelDefects::newFlatDepth(double length, double radius) {
  const double half_angle = std::asin(std::min(1.0, 0.5 * length / radius));
  return radius * (1.0 - std::cos(half_angle));
}

double WheelDefects::roundedFlatMaxDepth(double length, double radius) {
  return length * length / (2.0 * kPi * kPi * radius);
}

void WheelDefects::evaluate(std::uint32_t wheel, double beta, double& depth, double& d_depth_d_beta) const noexcept {
  depth = d_depth_d_beta = 0.0;
  if (wheel + 1 >= first_.size()) return;
  for (std::uint32_t i = first_[wheel]; i < first_[wheel + 1]; ++i) {
    const WheelDefect& d = defects_[i];
    const double psi = wrapAngle(beta - d.angle);
    if (d.shape == WheelDefectShape::kOutOfRound) {
      depth += d.amplitude * std::cos(d.order * psi);
      d_depth_d_beta -= d.amplitude * d.order * std::sin(d.order * psi);
    } else if (d.rounded) {
      // x = r psi along the circumference; a cosine dip over |x| <= L / 2.
      const double x = radius_ * psi;
      if (std::abs(x) > 0.5 * d.length) continue;
      const double k = 2.0 * kPi / d.length;
      depth += 0.5 * d.depth * (1.0 + std::cos(k * x));
      d_depth_d_beta -= 0.5 * d.depth * k * radius_ * std::sin(k * x);
    } else {
      // The flat spans |psi| <= theta0; turned by psi, the wheel rests on the edge at theta0 - |psi| from
      // the contact direction, its centre r (1 - cos(theta0 - |psi|)) lower than on a round wheel.
      const double theta0 = std::asin(0.5 * d.length / radius_);
      const double a = std::abs(psi);
      if (a > theta0) continue;
      depth += radius_ * (1.0 - std::cos(theta0 - a));
      d_depth_d_beta -= radius_ * std::sin(theta0 - a) * (psi < 0.0 ? -1.0 : 1.0);
    }
  }
}

}  // namespace rail::contact
