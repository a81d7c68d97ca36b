// Local vertical defects of the rails, placed by arc length: a dipped rail joint (a V of total angle
// 2 alpha whose ramps meet at the joint, optionally with an open gap between the rail ends) and a weld (a
// cosine bump or dip). Each adds a height z(s) to a rail's surface along the rail frame's b axis. Built once from the
// scene's track.defects (when effects.track_defects is on), constant afterwards; TrackGeometry::rail adds them, so the
// contact on the rigid and on the deformed rails sees them alike. doc/geometry.md, "Local defects", has the shapes.
#pragma once

#include <vector>

namespace rail::contact {

enum class RailSide;

enum class DefectShape {
  kDippedJoint,  // z = -alpha (L/2 - |x|) for |x| <= L/2, x = s - s_centre, alpha = dip_angle / 2; with a
                 // gap g, also -(r - sqrt(r^2 - (g/2 - |x|)^2)) for |x| <= g/2: the drop of a wheel of
                 // radius r bridging the gap, pivoting on one rail end and then on the other
  kWeld,         // z = height (1 + cos(2 pi x / L)) / 2 for |x| <= L/2
};

struct RailDefect {
  DefectShape shape = DefectShape::kDippedJoint;
  double s_centre = 0.0;      // m, the joint or the weld's centre
  double length = 0.0;        // m, extent L (a joint: both ramps together)
  double dip_angle = 0.0;     // rad, a joint's total angle 2 alpha between its two ramps (> 0)
  double height = 0.0;        // m, a weld's height at its centre (> 0 a bump, < 0 a dip)
  double gap = 0.0;           // m, a joint's open gap between the rail ends (0: closed)
  double wheel_radius = 0.0;  // m, radius of the wheels that bridge the gap (the vehicle's nominal radius)
  bool left = true;           // on the left rail
  bool right = true;          // on the right rail
};

class TrackDefects {
 public:
  TrackDefects() = default;
  // The scene loader checks each field (file, field and value in its message); a defect whose length is
  // not positive and finite is left out here.
  explicit TrackDefects(std::vector<RailDefect> defects);

  bool empty() const { return defects_.empty(); }
  const std::vector<RailDefect>& defects() const { return defects_; }

  // Sum of the defects' heights (m) on `side` at s and its slope dz/ds; 0 away from every defect.
  // No allocation; a binary search over the defects sorted by centre.
  void evaluate(RailSide side, double s, double& z, double& dz_ds) const noexcept;

 private:
  std::vector<RailDefect> defects_;  // sorted by s_centre
  double half_length_max_ = 0.0;
};

}  // namespace rail::contact
