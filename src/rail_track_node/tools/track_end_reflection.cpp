// Reflection of flexural waves at the ends of the FE track (program, not a test): for each frequency and
// direction, the reflected energy fraction with the data file's absorbing ends and with free ends (see
// rail_track_node/end_reflection.hpp for the method). Prints a table and writes it as CSV.
//
// Usage: track_end_reflection [--track FILE] [--freqs HZ,HZ,...] [--cycles N] [--no-damping] [--csv FILE]
// Defaults: config/track/paper_track.yaml, 300,400,500,700,1000,1500,2000 Hz, 5 cycles, track damping on,
// no CSV. --no-damping removes the track's own damping (Rayleigh damping of rails and sleepers, dampers of
// pads, ballast and sleeper interaction) and keeps the end dashpots: what the ends alone send back.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <rail_contact/tool_args.hpp>
#include <rail_core/testing/fixtures.hpp>

#include "rail_track_node/end_reflection.hpp"
#include "rail_track_node/track_data.hpp"

namespace rt = rail::track;

namespace {

const char* const kUsage =
    "usage: track_end_reflection [--track FILE] [--freqs HZ,HZ,...] [--cycles N] [--no-damping] [--csv FILE]\n"
    "Reflected energy fraction of a bending wave at the FE track's ends, with the data file's absorbing ends\n"
    "and with free ends, vertical and lateral, per frequency. Defaults: config/track/paper_track.yaml,\n"
    "300,400,500,700,1000,1500,2000 Hz, 5 cycles, track damping on (--no-damping: the ends alone), no CSV.\n";

}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, rail::tools::kOwnOptions)) return 0;
  std::string track = rail::core::fixtures::configDir() + "/track/paper_track.yaml", csv;
  std::vector<double> freqs = {300, 400, 500, 700, 1000, 1500, 2000};
  int cycles = 5;
  bool damping = true;
  for (rail::tools::Options o(argc, argv, "track_end_reflection"); o.next();) {
    if (o.is("--track"))
      track = o.value();
    else if (o.is("--csv"))
      csv = o.value();
    else if (o.is("--no-damping"))
      damping = false;
    else if (o.is("--cycles"))
      cycles = static_cast<int>(o.positive());
    else if (o.is("--freqs"))
      freqs = o.positives();
    else
      o.unknown();
  }
  rt::TrackData data;
  try {
    data = rt::loadTrackData(track);
  } catch (const std::exception& e) {
    std::cerr << "track_end_reflection: " << e.what() << "\n";
    return 2;
  }
  if (!damping) rt::removeTrackDamping(data);
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    if (!out) {
      std::cerr << "track_end_reflection: cannot write " << csv << "\n";
      return 2;
    }
    out << "direction,f_Hz,group_velocity_m_per_s,reflected_fraction_absorbing,reflected_fraction_free\n";
  }
  std::printf("track %s (track damping %s), absorbing ends designed for %.0f Hz; burst of %d cycles\n", track.c_str(),
              damping ? "on" : "off", data.absorbing_ends.design_frequency, cycles);
  std::printf("%-9s %7s %9s %12s %12s %8s %8s %7s\n", "direction", "f [Hz]", "c_g [m/s]", "absorbing", "free ends",
              "short[m]", "ref[m]", "wall[s]");
  for (const bool lateral : {false, true}) {
    for (const double f : freqs) {
      rt::EndReflectionOptions o;
      o.frequency = f;
      o.cycles = cycles;
      o.lateral = lateral;
      const char* dir = lateral ? "lateral" : "vertical";
      try {
        const auto t0 = std::chrono::steady_clock::now();
        rt::TrackData absorbing = data, free_ends = data;
        absorbing.absorbing_ends.enabled = true;
        free_ends.absorbing_ends.enabled = false;
        const rt::EndReflectionResult ra = rt::measureEndReflection(absorbing, o);
        const rt::EndReflectionResult rf = rt::measureEndReflection(free_ends, o);
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("%-9s %7.0f %9.0f %11.2f%% %11.2f%% %8.1f %8.1f %7.1f\n", dir, f, ra.group_velocity,
                    100.0 * ra.reflected_energy_fraction, 100.0 * rf.reflected_energy_fraction, ra.short_length,
                    ra.reference_length, wall);
        std::fflush(stdout);
        if (out)
          out << dir << "," << f << "," << ra.group_velocity << "," << ra.reflected_energy_fraction << ","
              << rf.reflected_energy_fraction << "\n";
      } catch (const std::invalid_argument& e) {
        std::printf("%-9s %7.0f  (skipped: %s)\n", dir, f, e.what());
      }
    }
  }
  return 0;
}
