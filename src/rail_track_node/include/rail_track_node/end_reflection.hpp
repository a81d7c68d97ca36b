// How much of a flexural wave the end of the FE track sends back (analysis, not the time loop).
//
// A tone burst (a sine of `cycles` periods at `frequency` under a Hann window) pushes the left rail near
// the right end of a short straight track; the rail's velocity is recorded a little before that end. The
// same burst on a reference track that extends far beyond both ends of the short one (so that nothing its
// ends return reaches the observation point within the window) gives the incident wave alone. The
// difference of the two records is what the short track's end sent back, and
//   reflected energy fraction = sum (v_short - v_reference)^2 / sum v_reference^2
// over the window (for one propagating wave, its energy flux is proportional to v^2 at a fixed frequency).
#pragma once

#include "rail_track_node/track_data.hpp"

namespace rail {
namespace track {

struct EndReflectionOptions {
  double frequency = 500.0;       ///< centre frequency of the burst, Hz
  int cycles = 5;                 ///< periods under the Hann window
  bool lateral = false;           ///< false: vertical force and velocity (world z); true: lateral (world y)
  double length = 30.0;           ///< short track at least, m (lengthened, in whole bays, until its left end's
                                  ///< echo arrives after the window)
  double load_from_end = 9.6;     ///< load to the short track's right end, m
  double observe_from_end = 2.4;  ///< observation point to the right end, m (a few wavelengths: no near field)
  double dt = 2e-5;               ///< Newmark step, s
};

struct EndReflectionResult {
  double reflected_energy_fraction = 0.0;             ///< sum (v_short - v_ref)^2 / sum v_ref^2
  double group_velocity = 0.0;                        ///< of the beam on the smeared foundation at `frequency`, m/s
  double cut_off_frequency = 0.0;                     ///< below it no flexural wave propagates, Hz
  double window = 0.0;                                ///< recorded time, s
  double short_length = 0.0, reference_length = 0.0;  ///< m
  int free_dofs_short = 0, free_dofs_reference = 0;
};

/// Runs the two tracks built from `data` (absorbing ends as data.absorbing_ends says) and measures the
/// reflected energy fraction. Throws std::invalid_argument for a frequency at or below the cut-off of the
/// direction (nothing propagates to the end there) or for geometry that does not fit.
EndReflectionResult measureEndReflection(const TrackData& data, const EndReflectionOptions& options);

}  // namespace track
}  // namespace rail
