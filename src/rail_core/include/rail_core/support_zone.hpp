// Zones of the track whose support differs from the track data's: the rail pads' and the ballast's
// stiffness and damping scaled over a range of arc length, reached through a linear ramp at each end of
// the range (a transition onto a bridge or a slab, a soft spot, a stiff crossing), and hanging (voided)
// sleepers: a gap between the sleepers and the ballast that closes under load. Read from the scene's
// track.support with effects.support_variation; applied to every sleeper's pads and ballast when the FE
// track is meshed.
#pragma once

#include <vector>

namespace rail::core {

struct SupportZone {
  double s_from = 0.0;  // m, where the ramp up starts
  double s_to = 0.0;    // m, where the ramp down ends
  double ramp = 0.0;    // m, length of each ramp (0: a step at each end)
  // Factors on the track data's values inside the zone [-].
  double pad_stiffness = 1.0;
  double pad_damping = 1.0;
  double ballast_stiffness = 1.0;
  double ballast_damping = 1.0;
  // Hanging sleepers: the ballast under each sleeper in the zone bears only in compression, once a void of
  // sleeper_gap (m; within a ramp a share of it) has closed.
  bool hanging = false;
  double sleeper_gap = 0.0;
};

// The four factors at arc length s, each the product over the zones containing s; within a ramp a zone's
// factor goes linearly from 1 at its outer end to the full factor at its inner end (a hanging zone's gap
// from 0 to its full value).
struct SupportFactors {
  double pad_stiffness = 1.0;
  double pad_damping = 1.0;
  double ballast_stiffness = 1.0;
  double ballast_damping = 1.0;
  bool hanging = false;      // in a hanging zone: unilateral ballast
  double sleeper_gap = 0.0;  // m, the largest of the hanging zones' gaps at s
};

inline SupportFactors supportFactors(const std::vector<SupportZone>& zones, double s) {
  SupportFactors f;
  for (const SupportZone& z : zones) {
    if (!(s >= z.s_from && s <= z.s_to)) continue;
    const double inside = s - z.s_from < z.s_to - s ? s - z.s_from : z.s_to - s;  // to the nearer end
    const double w = z.ramp > 0.0 && inside < z.ramp ? inside / z.ramp : 1.0;
    f.pad_stiffness *= 1.0 + w * (z.pad_stiffness - 1.0);
    f.pad_damping *= 1.0 + w * (z.pad_damping - 1.0);
    f.ballast_stiffness *= 1.0 + w * (z.ballast_stiffness - 1.0);
    f.ballast_damping *= 1.0 + w * (z.ballast_damping - 1.0);
    if (z.hanging) {
      f.hanging = true;
      f.sleeper_gap = w * z.sleeper_gap > f.sleeper_gap ? w * z.sleeper_gap : f.sleeper_gap;
    }
  }
  return f;
}

}  // namespace rail::core
