// Where the per-wheel contact evaluation spends its time, for a run's cost profile
// (rail_core/cost_profile.hpp). Owned by the caller and passed to WheelContactModel::evaluate; plain
// numbers, no allocation.
#pragma once

namespace rail {
namespace contact {

/// Accumulated over the evaluations it was passed to (wall seconds from std::chrono::steady_clock).
struct ContactCost {
  double detection_seconds = 0.0;         ///< contact searches, tread and flange
  double flange_detection_seconds = 0.0;  ///< the flange searches alone (part of detection_seconds)
  double forces_seconds = 0.0;            ///< normal (Hertz) and creep forces (creepages, Polach), wrenches
  long evaluations = 0;                   ///< wheel evaluations
  long flange_searches = 0;               ///< flange contact searches run (0 with effects.flange_contact off)
  long creep_evaluations = 0;             ///< creep-force (Polach) evaluations
  long spin_evaluations = 0;              ///< of those, with the spin terms (0 with effects.spin_creepage off)
};

}  // namespace contact
}  // namespace rail
