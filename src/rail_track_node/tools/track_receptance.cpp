// Point receptance of a straight track built from a track data file (program, not a test): vertical and
// lateral, above a sleeper and at mid-span of the left rail near the middle of the track, at log-spaced
// frequencies; written as CSV. Prints the track resonance and pinned-pinned frequencies found.
//
// Usage: track_receptance [--track FILE] [--length M] [--gauge M] [--points N] [--f-min HZ] [--f-max HZ]
//                         [--no-damping] [--rail-beta S] [--no-absorbing-ends] [--csv FILE]
// Defaults: config/track/paper_track.yaml, 80 m, gauge 1.668 m, 160 points, 10 Hz - 3 kHz,
// track damping and absorbing ends on, CSV receptance.csv. --rail-beta replaces the rail's
// stiffness-proportional Rayleigh coefficient (s), e.g. to see the pinned-pinned resonance that the
// data file's value damps out.
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include <rail_contact/tool_args.hpp>
#include <rail_core/scene_loader.hpp>
#include <rail_core/testing/fixtures.hpp>

#include "rail_track_node/receptance.hpp"
#include "rail_track_node/scene_track.hpp"

namespace rt = rail::track;

namespace {

constexpr double kPi = 3.14159265358979323846;

const char* const kUsage =
    "usage: track_receptance [--track FILE] [--length M] [--gauge M] [--points N] [--f-min HZ] [--f-max HZ]\n"
    "                        [--no-damping] [--rail-beta S] [--no-absorbing-ends] [--csv FILE]\n"
    "Point receptance of a straight FE track, vertical and lateral, above a sleeper and at mid-span, as CSV.\n"
    "Defaults: config/track/paper_track.yaml, 80 m, gauge 1.668 m, 160 points, 10 Hz - 3 kHz, damping and\n"
    "absorbing ends on, receptance.csv. --rail-beta replaces the rail's stiffness-proportional Rayleigh\n"
    "coefficient (s).\n";

}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, rail::tools::kOwnOptions)) return 0;
  std::string track = rail::core::fixtures::configDir() + "/track/paper_track.yaml", csv = "receptance.csv";
  double length = 80.0, gauge = 1.668, f_min = 10.0, f_max = 3000.0;
  int points = 160;
  bool damping = true, absorbing = true;
  double rail_beta = -1.0;  // < 0: the data file's
  rail::tools::Options o(argc, argv, "track_receptance");
  while (o.next()) {
    if (o.is("--track"))
      track = o.value();
    else if (o.is("--length"))
      length = o.number();
    else if (o.is("--gauge"))
      gauge = o.number();
    else if (o.is("--points"))
      points = static_cast<int>(o.number());
    else if (o.is("--f-min"))
      f_min = o.number();
    else if (o.is("--f-max"))
      f_max = o.number();
    else if (o.is("--no-damping"))
      damping = false;
    else if (o.is("--rail-beta"))
      rail_beta = o.number();
    else if (o.is("--no-absorbing-ends"))
      absorbing = false;
    else if (o.is("--csv"))
      csv = o.value();
    else
      o.unknown();
  }
  if (!(f_min > 0.0 && f_max > f_min) || points < 3) o.fail("need 0 < f-min < f-max and at least 3 points");

  try {
    // The track goes through the same scene path as the node: a straight moving-load scene.
    std::ostringstream scene_text;
    scene_text << "name: receptance\ntrack:\n  gauge: " << gauge << "\n  data: " << track
               << "\n  segments:\n    - {type: straight, length: " << length << "}\n"
               << "moving_loads:\n  loads:\n    - {vertical: 0.0}\n"
               << "effects:\n  track_damping: " << (damping ? "true" : "false")
               << "\n  absorbing_ends: " << (absorbing ? "true" : "false") << "\nsolver:\n  end: {time: 1.0}\n";
    const rail::core::Scene scene = rail::core::loadSceneText(scene_text.str(), "receptance.yaml", ".");
    const auto t0 = std::chrono::steady_clock::now();
    rt::SceneTrack t = rt::buildSceneTrack(scene);
    if (rail_beta >= 0.0) {
      // Rebuild with the rail's stiffness-proportional damping replaced.
      rt::TrackData data = t.model.data;
      data.rail.rayleigh_beta = rail_beta;
      rt::MeshOptions mo;
      mo.s_start = scene.track.start_arc_length;
      mo.track_length = scene.track.length();
      t.model = rt::buildTrackModel(data, mo, rt::seatPlaneFrames(t.geometry, t.seat_below_centre));
    }
    const rt::TrackMesh& mesh = t.model.mesh;
    const double a = mesh.sleeper_spacing;
    const double s_sleeper = mesh.s_start + std::floor(0.5 * (mesh.n_sleepers - 1)) * a;
    const double s_mid = s_sleeper + 0.5 * a;
    using D = rt::ReceptancePoint::Direction;
    const std::vector<rt::ReceptancePoint> pts = {{rt::kLeftRail, s_sleeper, D::kVertical},
                                                  {rt::kLeftRail, s_mid, D::kVertical},
                                                  {rt::kLeftRail, s_sleeper, D::kLateral},
                                                  {rt::kLeftRail, s_mid, D::kLateral}};
    const char* names[4] = {"vert_sleeper", "vert_midspan", "lat_sleeper", "lat_midspan"};
    const double head_arm = t.rail_height - t.model.data.layout.rail_centroid_height;
    rt::ReceptanceSolver solver(t.model, head_arm, pts);
    std::printf(
        "track %s: %.1f m straight, %d free DOFs, sleeper at s = %.2f m, mid-span at %.2f m, damping %s, "
        "absorbing ends %s\n",
        track.c_str(), length, t.model.system.size(), s_sleeper, s_mid, damping ? "on" : "off",
        absorbing ? "on" : "off");

    const std::vector<double> f = rt::logSpacedFrequencies(f_min, f_max, points);
    std::vector<std::vector<double>> mag(4, std::vector<double>(points)), phase(4, std::vector<double>(points));
    std::vector<std::complex<double>> r;
    for (int k = 0; k < points; ++k) {
      solver.solve(f[k], r);
      for (int p = 0; p < 4; ++p) {
        mag[p][k] = std::abs(r[p]);
        phase[p][k] = std::arg(r[p]) * 180.0 / kPi;
      }
      if ((k + 1) % 20 == 0) std::fprintf(stderr, "  %d / %d frequencies\n", k + 1, points);
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

    std::ofstream out(csv);
    if (!out) throw std::runtime_error("cannot write " + csv);
    out << "f_Hz";
    for (const char* n : names) out << ',' << n << "_mag_m_per_N," << n << "_phase_deg";
    out << '\n';
    out.precision(8);
    for (int k = 0; k < points; ++k) {
      out << f[k];
      for (int p = 0; p < 4; ++p) out << ',' << mag[p][k] << ',' << phase[p][k];
      out << '\n';
    }

    // Track resonance: the peak of the vertical receptance above a sleeper below 600 Hz (rail and sleeper
    // mass on the pad + ballast stiffness). Pinned-pinned: a peak of the vertical mid-span receptance above
    // 600 Hz (the rail vibrating between the sleepers with nodes at them); heavy rail damping removes it.
    const double f_track = rt::peakFrequency(f, mag[0], 20.0, 600.0);
    const double f_lat = rt::peakFrequency(f, mag[2], 20.0, 600.0);
    int pp = -1;
    for (int k = 1; k + 1 < points; ++k)
      if (f[k] > 600.0 && mag[1][k] > mag[1][k - 1] && mag[1][k] >= mag[1][k + 1] && (pp < 0 || mag[1][k] > mag[1][pp]))
        pp = k;
    const double f_pp_eb = rt::pinnedPinnedFrequency(t.model.data.rail, a);
    std::printf("static vertical receptance above a sleeper (at %.0f Hz): %.3e m/N\n", f[0], mag[0][0]);
    std::printf("vertical track resonance (peak above a sleeper): %.0f Hz\n", f_track);
    std::printf("lateral track resonance (peak above a sleeper):  %.0f Hz\n", f_lat);
    if (pp >= 0)
      std::printf(
          "vertical pinned-pinned (peak of the mid-span receptance): %.0f Hz (Euler-Bernoulli on rigid "
          "supports: %.0f Hz)\n",
          rt::peakFrequency(f, mag[1], f[pp - 1], f[pp + 1]), f_pp_eb);
    else
      std::printf(
          "vertical pinned-pinned: no peak of the mid-span receptance above 600 Hz (damped out; "
          "Euler-Bernoulli on rigid supports: %.0f Hz)\n",
          f_pp_eb);
    std::printf("wrote %s (%d frequencies, %.1f s)\n", csv.c_str(), points, wall);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "track_receptance: %s\n", e.what());
    return 2;
  }
  return 0;
}
