// Defects of the wheels' running surfaces: wheel flats (new, with sharp edges, or rounded by wear) and
// out-of-roundness (one harmonic of the radius round the wheel). Each wheel's defects turn with the wheel:
// they are placed by an angle in the wheelset's body frame, so the wheelset's rolling angle carries them
// round and an impact repeats once a revolution. Built once from the scene's vehicle.wheel_defects (when
// effects.wheel_defects is on), constant afterwards; WheelContactModel::evaluate applies them to the
// penetration of each contact. doc/forces.md, "Wheel defects", has the shapes and what they leave out.
#pragma once

#include <cstdint>
#include <vector>

namespace rail::contact {

enum class WheelDefectShape {
  kFlat,        // a chord of length L cut off the wheel; new: sharp edges, rounded: a cosine dip of depth d
  kOutOfRound,  // radius r0 - A cos(n psi): a harmonic of order n with a low spot of depth A at psi = 0
};

struct WheelDefect {
  WheelDefectShape shape = WheelDefectShape::kFlat;
  std::uint32_t wheel = 0;  // wheel index, 2 * wheelset + side (0 left, 1 right)
  // rad: where the defect's low spot is at t = 0, measured in the wheelset's x-z plane from its -z axis
  // toward +x (forward), the same way as the wheel parameter s_w of contact_detection.hpp
  double angle = 0.0;
  double length = 0.0;     // flat: chord length L (new) or length of the dip (rounded) [m]
  bool rounded = false;    // flat: a cosine dip of depth `depth` instead of the sharp-edged chord
  double depth = 0.0;      // rounded flat: depth d [m]
  int order = 0;           // out-of-roundness: harmonic order n (1 = eccentricity)
  double amplitude = 0.0;  // out-of-roundness: A [m]
};

class WheelDefects {
 public:
  WheelDefects() = default;
  // The scene loader checks each field (file, field and value in its message); radius is the wheels'
  // nominal rolling radius r0 [m].
  WheelDefects(std::vector<WheelDefect> defects, double radius);

  bool empty() const { return defects_.empty(); }
  const std::vector<WheelDefect>& defects() const { return defects_; }

  // How far the running surface of wheel `wheel` lies inside the round wheel where the contact is, at
  // material angle beta [rad] (wheelset frame, as WheelDefect::angle): depth [m] and d depth / d beta
  // [m/rad]. For a flat this is the drop of the wheel centre rolling over it on a rigid rail (the
  // equivalent irregularity: on a new flat the wheel pivots about the flat's edges, not along the chord).
  // 0 for a wheel without defects. No allocation.
  void evaluate(std::uint32_t wheel, double beta, double& depth, double& d_depth_d_beta) const noexcept;

  // Depth of a new flat of chord length L on a wheel of radius r: r (1 - cos(asin(L / 2r))) [m].
  static double newFlatDepth(double length, double radius);
  // The deepest rounded flat of length L a wheel of radius r can follow on a rigid rail: the dip's
  // curvature at its bottom equals the wheel's own, d = L^2 / (2 pi^2 r) [m].
  static double roundedFlatMaxDepth(double length, double radius);

 private:
  std::vector<WheelDefect> defects_;  // sorted by wheel
  std::vector<std::uint32_t> first_;  // first_[w] .. first_[w + 1]: wheel w's defects
  double radius_ = 0.0;
};

}  // namespace rail::contact
