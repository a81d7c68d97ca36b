// The track side's run loop (CosimTrackRun) driven by recorded wheel states through a ReplayTransport in
// one thread: the end rules (a vehicle that closes at solver.end finishes the run; one that closes earlier
// went away, exit 4, unless the frames are a replay), a refused frame (exit 3, the reason named), and the
// output instants at output.rate.
#include <gtest/gtest.h>

#include <string>

#include <rail_core/coupling/replay_transport.hpp>
#include <rail_core/exit_codes.hpp>
#include <rail_core/scene_loader.hpp>
#include <rail_core/testing/fixtures.hpp>

#include "rail_track_node/cosim_track.hpp"
#include "rail_track_node/cosim_track_run.hpp"

namespace rt = rail::track;
namespace cc = rail::core::coupling;
using rail::core::Scene;

namespace {

// Straight 30 m of the paper's track, rigid_fe (contact only, no FE), track step 1 ms, to t = 0.02 s, outputs
// at 200 Hz.
// end: the scene's solver.end (an arc length leaves the end to the vehicle, which then needs a speed).
Scene scene(const std::string& end = "{time: 0.02}", const std::string& speed = "0.0") {
  const std::string text =
      "name: t\ntrack:\n  gauge: 1.668\n  cant_reference_width: 1.733\n  data: ../track/paper_track.yaml\n"
      "  segments:\n    - {type: straight, length: 30.0}\n"
      "vehicle:\n  data: ../vehicle/paper_coach.yaml\n  start_arc_length: 25.0\n  speed: " +
      speed +
      "\n"
      "  back_to_back: 1.592\n  nominal_radius: 0.445\n"
      "effects:\n  track_model: rigid_fe\n"
      "solver:\n  track_step: 1.0e-3\n  vehicle_max_step: 1.0e-3\n  end: " +
      end +
      "\n  exchange_timeout: 1.0\n"
      "output:\n  rate: 200\n";
  return rail::core::fixtures::sceneFromText(text, "t.yaml");
}

// `wheels` wheels standing 5 cm above the rails (no contact) at instants 0, dt, ..., t_last.
cc::RecordedStates recording(int wheels, double t_last, double dt = 0.005) {
  cc::RecordedStates r;
  r.source = "test recording";
  for (int k = 0; k * dt <= t_last + 1e-12; ++k) {
    cc::WheelStateFrame f(wheels);
    f.count = static_cast<std::uint32_t>(wheels);
    for (int i = 0; i < wheels; ++i) {
      cc::WheelState& w = f.wheels[static_cast<std::size_t>(i)];
      w.id = static_cast<std::uint32_t>(i);
      w.arc_length = 25.0 - 2.5 * (i / 2);
      w.p_wheel_in_world = Eigen::Vector3d(w.arc_length, i % 2 == 0 ? 0.75 : -0.75, 0.445 + 0.05);
    }
    r.times.push_back(k * dt);
    r.frames.push_back(f);
  }
  return r;
}

struct Outcome {
  rt::TrackRunStatus status;
  int exit_code;
  std::string message;
  int steps;
  int outputs;
};

Outcome run(const Scene& sc, cc::RecordedStates rec, bool replay) {
  rt::CosimTrackOptions options;
  options.window.vehicle_length = 7.5;
  rt::CosimTrack track(rt::resolveCosimTrack(sc), options);
  cc::ReplayTransport transport(std::move(rec), sc.solver.track_step, sc.hash, 0.0);
  rt::CosimTrackRun loop(rail::core::runSettings(sc), track, transport, {"/vehicle_under_test", replay, nullptr});
  Outcome o{rt::TrackRunStatus::kRunning, 0, "", 0, 0};
  while ((o.status = loop.step()) == rt::TrackRunStatus::kRunning) {
    ++o.steps;
    if (loop.outputDue()) ++o.outputs;
  }
  loop.close();
  o.exit_code = loop.exitCode();
  o.message = loop.message();
  return o;
}

}  // namespace

TEST(CosimTrackRun, AVehicleClosingAtSolverEndFinishesTheRun) {
  const Scene sc = scene();
  const Outcome o = run(sc, recording(sc.wheelCount(), 0.02), false);
  EXPECT_EQ(o.status, rt::TrackRunStatus::kFinished) << o.message;
  EXPECT_EQ(o.exit_code, 0);
  EXPECT_EQ(o.steps, 21);   // t = 0, 1, ..., 20 ms
  EXPECT_EQ(o.outputs, 5);  // t = 0, 5, 10, 15, 20 ms at 200 Hz
}

TEST(CosimTrackRun, AVehicleClosingBeforeSolverEndWentAway) {
  const Scene sc = scene();
  const Outcome o = run(sc, recording(sc.wheelCount(), 0.01), false);
  EXPECT_EQ(o.status, rt::TrackRunStatus::kFailed);
  EXPECT_EQ(o.exit_code, rail::core::kExitPeerTimeout);
  EXPECT_NE(o.message.find("the vehicle node /vehicle_under_test went away after step 10 (t = 0.010000 s), "
                           "before solver.end"),
            std::string::npos)
      << o.message;
  EXPECT_EQ(o.steps, 11);
}

// With an end by arc length only the vehicle knows when it has arrived: its closing ends the run, exit 0
// (the whole paper scene ends at s = 499 m).
TEST(CosimTrackRun, AVehicleClosingAtAnArcLengthEndFinishesTheRun) {
  const Scene sc = scene("{arc_length: 29.0}", "10.0");
  const Outcome o = run(sc, recording(sc.wheelCount(), 0.01), false);
  EXPECT_EQ(o.status, rt::TrackRunStatus::kFinished) << o.message;
  EXPECT_EQ(o.exit_code, 0) << o.message;
  EXPECT_EQ(o.steps, 11);
}

TEST(CosimTrackRun, AReplayEndsWhereItsRecordingEnds) {
  const Scene sc = scene();
  const Outcome o = run(sc, recording(sc.wheelCount(), 0.01), true);
  EXPECT_EQ(o.status, rt::TrackRunStatus::kFinished) << o.message;
  EXPECT_EQ(o.exit_code, 0);
  EXPECT_EQ(o.steps, 11);
}

TEST(CosimTrackRun, AFrameWithTheWrongWheelCountIsRefused) {
  const Scene sc = scene();
  const Outcome o = run(sc, recording(sc.wheelCount() - 2, 0.02), false);
  EXPECT_EQ(o.status, rt::TrackRunStatus::kFailed);
  EXPECT_EQ(o.exit_code, rail::core::kExitPeerRefused);
  EXPECT_EQ(o.message,
            "exchange with the vehicle node /vehicle_under_test failed at step 0: track: wheel states "
            "from the vehicle refused at step 0: 6 wheels received, 8 expected");
}

TEST(CosimTrackRun, AFrameWithABadWheelIdIsRefusedByTheTrack) {
  const Scene sc = scene();
  cc::RecordedStates rec = recording(sc.wheelCount(), 0.02);
  for (cc::WheelStateFrame& f : rec.frames) f.wheels[3].id = 99;
  const Outcome o = run(sc, rec, false);
  EXPECT_EQ(o.status, rt::TrackRunStatus::kFailed);
  EXPECT_EQ(o.exit_code, rail::core::kExitPeerRefused);
  EXPECT_EQ(o.message, "step 0: the vehicle's frame was refused (bad wheel id)");
}
