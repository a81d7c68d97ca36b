#include "rail_contact/track_defects.hpp"

#include <algorithm>
#include <cmath>
#include "rail_contact/track_geometry.hpp"

namespace rail::contact {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

TrackDefects::TrackDefects(std::vector<RailDefect> defects) {
  for (const RailDefect& d : defects)
    if (d.length > 0.0 && std::isfinite(d.length) && std::isfinite(d.s_centre)) defects_.push_back(d);
  for (const RailDefect& d : defects_) half_length_max_ = std::max(half_length_max_, 0.5 * d.length);
  std::stable_sort(defects_.begin(), defects_.end(),
                   [](const RailDefect& a, const RailDefect& b) { return a.s_centre < b.s_centre; });
}

void TrackDefects::evaluate(RailSide side, double s, double& z, double& dz_ds) const noexcept {
  z = dz_ds = 0.0;
  if (defects_.empty()) return;
  // Only defects whose centre lies within the longest half-length of s can reach it.
  auto it = std::lower_bound(defects_.begin(), defects_.end(), s - half_length_max_,
                             [](const RailDefect& d, double v) { return d.s_centre < v; });
  const bool left = side == RailSide::kLeft;
  for (; it != defects_.end() && it->s_centre <= s + half_length_max_; ++it) {
    const RailDefect& d = *it;
    if (left ? !d.left : !d.right) continue;
    const double x = s - d.s_centre;
    const double half = 0.5 * d.length;
    if (std::abs(x) > half) continue;
    if (d.shape == DefectShape::kDippedJoint) {
      const double alpha = 0.5 * d.dip_angle;
      z -= alpha * (half - std::abs(x));
      dz_ds += x < 0.0 ? -alpha : alpha;
      const double u = 0.5 * d.gap - std::abs(x);  // from the rail end the wheel pivots on
      if (u > 0.0 && d.wheel_radius > u) {
        const double root = std::sqrt(d.wheel_radius * d.wheel_radius - u * u);
        z -= d.wheel_radius - root;
        dz_ds += (x < 0.0 ? -u : u) / root;
      }
    } else {
      const double k = 2.0 * kPi / d.length;
      z += 0.5 * d.height * (1.0 + std::cos(k * x));
      dz_ds -= 0.5 * d.height * k * std::sin(k * x);
    }
  }
}

}  // namespace rail::contact
