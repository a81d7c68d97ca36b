// Track side of the co-simulation on a moving track window (solver.track_window.enabled) against the
// full-length FE track: 8 rigid wheels of the paper's coach (wheelsets 0, 2.7, 19.0 and 21.7 m behind the
// leading one) rolling at constant speed over at least two window moves, on a straight line and through
// a transition into a canted R = 500 m curve: the returned wheel forces (vertical and lateral, track
// frame) and the rail deflection at two sections agree within 1 % of their peaks, with 2 m and 5 m
// margins, the larger margin not worse. A wheel off the window is a reported status, not a step.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <rail_contact/profile.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/scene_loader.hpp>
#include <rail_core/testing/fixtures.hpp>

#include "rail_track_node/cosim_track.hpp"

namespace rt = rail::track;
namespace rc = rail::contact;
namespace cc = rail::core::coupling;
using rail::core::Scene;

namespace {

// The paper's track data and coach (Iberian gauge) on a 150 m line: straight, or 30 m straight + a 40 m
// transition (clothoid, cant ramp 0 -> 160 mm) + 80 m of R = 500 m left curve with 160 mm cant.
Scene lineScene(bool curve, double h) {
  char step[32];
  std::snprintf(step, sizeof step, "%.10g", h);
  const std::string segments =
      curve ? "    - {type: straight, length: 30.0}\n"
              "    - {type: transition, length: 40.0, direction: left, radius_start: 0, radius_end: 500.0,"
              " cant_start: 0.0, cant_end: 0.160}\n"
              "    - {type: circular, length: 80.0, direction: left, radius: 500.0, cant: 0.160}\n"
            : "    - {type: straight, length: 150.0}\n";
  const std::string text =
      "name: w\ntrack:\n  gauge: 1.668\n  cant_reference_width: 1.733\n  data: ../track/paper_track.yaml\n"
      "  segments:\n" +
      segments +
      "vehicle:\n  data: ../vehicle/paper_coach.yaml\n  start_arc_length: 60.0\n  speed: 30.0\n"
      "  back_to_back: 1.592\n  nominal_radius: 0.445\n  wheelsets: 4\n"
      "effects:\n  track_model: flexible\n"
      "solver:\n  track_step: " +
      std::string(step) + "\n  vehicle_max_step: " + std::string(step) + "\n  end: {time: 1.0}\n";
  return rail::core::fixtures::sceneFromText(text, "w.yaml");
}

// The paper coach's wheel span (Table 3: 2.7 m bogie wheelbase, 19 m between the bogie centres; the load
// points of config/vehicle/paper_coach.yaml span 0.65 .. 22.35 m), which the vehicle node sends in the
// handshake.
rt::CosimTrackOptions coachWindow() {
  rt::CosimTrackOptions o;
  o.window.vehicle_length = 21.7;
  return o;
}

Scene windowed(Scene sc, double margin) {
  sc.solver.track_window.enabled = true;
  sc.solver.track_window.behind = margin;
  sc.solver.track_window.ahead = margin;
  sc.solver.track_window.shift = 3.0;
  sc.solver.track_window.length = 0.0;
  return sc;
}

constexpr double kOffsets[4] = {0.0, 2.7, 19.0, 21.7};  // behind the leading wheelset, m (paper coach, Table 3)

// Rigid wheelsets on the design track at constant speed V: wheelset w's centre at arc length
// s_front - kOffsets[w], in the track frame (cant included) at height z above the centre line, yawed by
// a small angle (creep forces), spinning at V / r0 about the axle and following the curve's heading.
void fillFrame(const rc::TrackGeometry& geo, double s_front, double V, double z, long k, double h,
               cc::WheelStateFrame& f) {
  const double r0 = 0.445;
  const double taping_y = 0.5 * 1.592 + rc::flangeBackY(rc::makeS1002());
  f.count = 8;
  f.step = static_cast<std::uint64_t>(k);
  f.time = k * h;
  rc::TrackPoint tp;
  for (int ws = 0; ws < 4; ++ws) {
    const double s = s_front - kOffsets[ws];
    geo.centre(s, tp);
    const Eigen::Matrix3d yaw = Eigen::AngleAxisd(1e-3 * (ws - 1.5), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Matrix3d R = tp.R_track_to_world * yaw;
    const Eigen::Quaterniond q(R);
    const Eigen::Vector3d v = V * tp.R_track_to_world.col(0);
    const Eigen::Vector3d omega = R.col(1) * (V / r0) + tp.R_track_to_world.col(2) * (V * tp.curvature);
    for (int side = 0; side < 2; ++side) {
      const int id = 2 * ws + side;
      cc::WheelState& w = f.wheels[static_cast<std::size_t>(id)];
      w.id = static_cast<std::uint32_t>(id);
      const Eigen::Vector3d arm = R * Eigen::Vector3d(0.0, side == 0 ? taping_y : -taping_y, 0.0);
      w.p_wheel_in_world = tp.p_center_in_world + tp.R_track_to_world.col(2) * z + arm;
      w.arc_length = s;
      w.R_wheelset_to_world = q.toRotationMatrix();
      w.v_wheel_in_world = v + omega.cross(arm);
      w.omega_wheelset_in_world = omega;
    }
  }
}

struct History {
  std::vector<double> fz, fy;  // per step and wheel: wheel force in the track frame, N
  std::vector<double> sz, sy;  // per step, section and rail: rail deflection, m
  int moves = 0, rebuilds = 0, drops = 0, outside = 0;
  long unconverged = 0, clipped = 0, steps = 0;
};

// Runs the coach from s_front0 for `steps` steps of h at V; the wheels start at the nominal radius on the
// design rails (rails at their self-weight state) and are lowered by 0.7 mm over the first 20 ms (the
// loads rise to about the coach's static wheel load), then roll at that height.
History run(const Scene& sc, double s_front0, long steps, const double (&sections)[2]) {
  rt::CosimTrack track(rt::resolveCosimTrack(sc), coachWindow());
  History H;
  for (double s : sections) track.addSection(s);
  const rc::TrackGeometry& geo = track.geometry();
  const double V = 30.0, h = sc.solver.track_step, r0 = 0.445;
  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  rt::RailSectionDeflection def;
  rc::TrackPoint tp;
  for (long k = 0; k < steps; ++k) {
    const double t = k * h;
    const double z = r0 - 0.7e-3 * std::min(1.0, t / 0.02);
    const double s_front = s_front0 + V * t;
    fillFrame(geo, s_front, V, z, k, h, frame);
    const rt::CosimStepStatus status = track.step(frame, out);
    if (status != rt::CosimStepStatus::kOk) {
      ++H.outside;
      continue;
    }
    for (int i = 0; i < 8; ++i) {
      geo.centre(s_front - kOffsets[i / 2], tp);
      const Eigen::Vector3d f =
          tp.R_track_to_world.transpose() * out.wheels[static_cast<std::size_t>(i)].f_wheel_in_world;
      H.fz.push_back(f.z());
      H.fy.push_back(f.y());
    }
    for (int j = 0; j < 2; ++j) {
      track.sectionDeflection(j, def);
      for (int r = 0; r < 2; ++r) {
        H.sz.push_back(def.displacement[static_cast<std::size_t>(r)].z());
        H.sy.push_back(def.displacement[static_cast<std::size_t>(r)].y());
      }
    }
  }
  H.moves = track.windowMoves();
  H.rebuilds = track.windowRebuilds();
  H.drops = track.influenceCacheDrops();
  H.unconverged = track.newtonUnconverged();
  H.clipped = track.influenceClipped();
  H.steps = track.newmarkSteps();
  return H;
}

double peak(const std::vector<double>& a) {
  double p = 0.0;
  for (double x : a) p = std::max(p, std::abs(x));
  return p;
}
// Largest |a - b| over the history, as a fraction of the reference b's peak; entries of `stride`
// interleaved series (wheels, or sections x rails) each against its own series' peak.
double worst(const std::vector<double>& a, const std::vector<double>& b, int stride) {
  double e = 0.0;
  for (int c = 0; c < stride; ++c) {
    double p = 0.0, d = 0.0;
    for (std::size_t i = static_cast<std::size_t>(c); i < b.size(); i += static_cast<std::size_t>(stride)) {
      p = std::max(p, std::abs(b[i]));
      d = std::max(d, std::abs(a[i] - b[i]));
    }
    if (p > 0.0) e = std::max(e, d / p);
  }
  return e;
}

struct Agreement {
  double fz = 0.0, fy = 0.0, sz = 0.0, sy = 0.0;
};
Agreement compare(const History& w, const History& full) {
  Agreement a;
  a.fz = worst(w.fz, full.fz, 8);
  a.fy = worst(w.fy, full.fy, 8);
  // Sections: each section and rail against the peak of its own vertical (z) or lateral (y) history.
  a.sz = worst(w.sz, full.sz, 4);
  a.sy = worst(w.sy, full.sy, 4);
  return a;
}

// zone: a soft support zone (pads and ballast at half their stiffness, 61.8 .. 67.8 m, 1.2 m ramps) under
// the wheels' path and the second section: a window over it is no translated copy of the previous one.
// hanging: instead, the sleepers at 64.2 and 64.8 m hang over a 1.5 mm void that the wheels close.
void checkAgainstFull(bool curve, bool zone = false, bool hanging = false) {
  // h = 1e-4 s: the semi-implicit coupling is stable there and within 20 N of the 1e-5 s wheel load
  // (doc/cosim_track.md); both models take the same step, so it does not enter the comparison.
  const double h = 1e-4;
  const long steps = 3500;  // 0.35 s, 10.5 m at 30 m/s: at least 2 moves of 3 m with either margin
  const double s_front0 = 60.0;
  // First section just ahead of the leading wheel (passed at once); second reached by the leading wheel
  // after 0.23 s, after 2 moves of the window.
  const double sections[2] = {61.0, 67.0};
  Scene sc = lineScene(curve, h);
  if (zone) {
    rail::core::SupportZone z;
    z.s_from = 61.8;
    z.s_to = 67.8;
    z.ramp = 1.2;
    z.pad_stiffness = 0.5;
    z.ballast_stiffness = 0.5;
    sc.track.support = {z};
    sc.effects.support_variation = true;
  }
  if (hanging) {
    rail::core::SupportZone z;
    z.s_from = 64.1;
    z.s_to = 64.9;
    z.hanging = true;
    z.sleeper_gap = 1.5e-3;
    sc.track.support = {z};
    sc.effects.support_variation = true;
    zone = true;
  }
  const History full = run(sc, s_front0, steps, sections);
  ASSERT_EQ(full.outside, 0);
  ASSERT_EQ(full.steps, steps - 1);
  EXPECT_EQ(full.unconverged, 0);
  const double Qpeak = peak(full.fz), Ypeak = peak(full.fy);
  // The wheels carry load throughout and the lateral creep forces are not negligible.
  EXPECT_GT(Qpeak, 50e3);
  EXPECT_GT(Ypeak, 1e3);
  double previous = std::numeric_limits<double>::infinity();
  for (double margin : {2.0, 5.0}) {
    const History w = run(windowed(sc, margin), s_front0, steps, sections);
    ASSERT_EQ(w.outside, 0);
    ASSERT_EQ(w.steps, steps - 1);
    ASSERT_EQ(w.fz.size(), full.fz.size());
    EXPECT_EQ(w.unconverged, 0);
    EXPECT_EQ(w.clipped, 0);
    EXPECT_GE(w.moves, 2);
    // Straight line: every move reuses the matrices and factor (the cache is kept); curve: every move
    // refactorises and drops the influence columns.
    if (curve) {
      EXPECT_EQ(w.rebuilds, w.moves);
    } else if (zone) {
      EXPECT_GE(w.rebuilds, 1);  // a window over the zone differs from its predecessor
    } else {
      EXPECT_EQ(w.rebuilds, 0);
    }
    EXPECT_EQ(w.drops, w.rebuilds);
    const Agreement a = compare(w, full);
    std::printf(
        "%s%s%s, margins %.0f m: %d moves (%d rebuilt); |window - full| / peak: wheel Fz %.3g %%, Fy %.3g %%, "
        "section z %.3g %%, y %.3g %% (peaks Fz %.0f N, Fy %.0f N)\n",
        curve ? "curve" : "straight", zone && !hanging ? " over a soft zone" : "",
        hanging ? " over hanging sleepers" : "", margin, w.moves, w.rebuilds, 100 * a.fz, 100 * a.fy, 100 * a.sz,
        100 * a.sy, Qpeak, Ypeak);
    // 1 % of each quantity's peak, the target of the window design (doc/track_window.md: its own
    // moving-load comparison gives <= 0.15 % with 2 m margins). Over a support zone the track beyond a
    // window end is condensed as plain track, so a zone just ahead of the end is missing from it: with 2 m
    // margins the lateral forces differ by up to 2 % (measured 1.97 %, allowed 3 %), with the default 5 m
    // within the 1 %.
    const double tolerance = zone && margin < 5.0 ? 0.03 : 0.01;
    EXPECT_LT(a.fz, tolerance);
    EXPECT_LT(a.fy, tolerance);
    EXPECT_LT(a.sz, tolerance);
    EXPECT_LT(a.sy, tolerance);
    const double overall = std::max(std::max(a.fz, a.fy), std::max(a.sz, a.sy));
    // Larger margins agree as well or better (10 % slack on the worst figure: round-off level at 5 m).
    EXPECT_LE(overall, 1.1 * previous + 1e-6);
    previous = overall;
  }
}

}  // namespace

TEST(CosimTrackWindow, StraightLineMatchesFullLengthTrack) { checkAgainstFull(false); }

TEST(CosimTrackWindow, TransitionIntoCantedCurveMatchesFullLengthTrack) { checkAgainstFull(true); }

TEST(CosimTrackWindow, SoftSupportZoneMatchesFullLengthTrack) { checkAgainstFull(false, true); }

// The hanging sleepers' loads (relative to each window's piecewise-linear self-weight state) against the
// full-length track's (absolute): the same tolerances as a support zone.
TEST(CosimTrackWindow, HangingSleepersMatchFullLengthTrack) { checkAgainstFull(false, false, true); }

// A wheel that the window cannot cover (wheels spread over more than the window) is reported, nothing is
// evaluated or integrated, and a following good frame steps normally. Non-finite arc lengths too.
TEST(CosimTrackWindow, WheelOutsideWindowIsAStatus) {
  const Scene sc = windowed(lineScene(false, 1e-4), 2.0);
  rt::CosimTrack track(rt::resolveCosimTrack(sc), coachWindow());
  ASSERT_NE(track.trackWindow(), nullptr);
  EXPECT_EQ(track.sceneTrack(), nullptr);
  EXPECT_TRUE(track.flexible());
  const rc::TrackGeometry& geo = track.geometry();
  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  fillFrame(geo, 60.0, 30.0, 0.445, 0, 1e-4, frame);
  ASSERT_EQ(track.step(frame, out), rt::CosimStepStatus::kOk);
  fillFrame(geo, 60.0 + 3e-3, 30.0, 0.445, 1, 1e-4, frame);
  frame.wheels[7].arc_length = 60.0 - 50.0;  // last wheel 50 m behind the first: no window of 28.7 m holds both
  const long steps = track.newmarkSteps();
  EXPECT_EQ(track.step(frame, out), rt::CosimStepStatus::kWheelOutsideWindow);
  EXPECT_EQ(track.newmarkSteps(), steps);
  frame.wheels[7].arc_length = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(track.step(frame, out), rt::CosimStepStatus::kWheelOutsideWindow);
  fillFrame(geo, 60.0 + 3e-3, 30.0, 0.445, 1, 1e-4, frame);
  EXPECT_EQ(track.step(frame, out), rt::CosimStepStatus::kOk);
  EXPECT_EQ(track.newmarkSteps(), steps + 1);
  EXPECT_TRUE(track.trackWindow()->covers(60.0 + 3e-3 - 21.7, 60.0 + 3e-3));
  // The arbitrary-vector section overload has no meaning on a moving window.
  track.addSection(61.0);
  rt::RailSectionDeflection def;
  EXPECT_THROW(track.sectionDeflection(0, Eigen::VectorXd::Zero(10), def), std::runtime_error);
}

// The window is sized by the vehicle's wheel span, which the track side takes from the caller (the handshake),
// never from the vehicle's data file: without it the build is refused, naming the option.
TEST(CosimTrackWindow, RefusesAWindowWithoutTheWheelSpan) {
  const Scene sc = windowed(lineScene(false, 1e-4), 2.0);
  try {
    rt::CosimTrack track(rt::resolveCosimTrack(sc));
    FAIL() << "built without a wheel span";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("CosimTrackOptions::window.vehicle_length: the vehicle's wheel span (m, > 0) "
                                         "is needed for the track window"),
              std::string::npos)
        << e.what();
  }
}
