// The co-simulated vehicle (CosimVehicle) against the vehicle alone on the rigid track (VehicleSimulator):
// an in-process co-simulation over the LoopbackLink whose "track" side, in a second thread, evaluates the
// rigid-track wheel-rail contact from the wheel states it receives and returns the wheel-centre wrenches.
// With a rigid track both runs solve the same equations; they differ only by the coupling (contact
// evaluated at the track steps t_k and linearly extrapolated in between), which the paper's two rigid runs
// quantify (section 6: lateral 2.5e-5 m, angle of attack 4.7e-4 deg, vertical 8e-8 m).
#include <gtest/gtest.h>

#include <rail_contact/profile.hpp>
#include <rail_contact/rail_deformation.hpp>
#include <rail_contact/track_geometry.hpp>
#include <rail_contact/wheel_contact.hpp>
#include <rail_core/coupling/loopback_transport.hpp>
#include <rail_core/coupling/protocol.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/scene_loader.hpp>
#include <rail_core/testing/fixtures.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <rail_core/exit_codes.hpp>
#include "rail_vehicle_node/cosim_vehicle.hpp"
#include "rail_vehicle_node/vehicle_loader.hpp"
#include "rail_vehicle_node/vehicle_run.hpp"
#include "rail_vehicle_node/vehicle_simulator.hpp"

namespace rail::vehicle {
namespace {

namespace rc = rail::contact;
namespace cc = rail::core::coupling;

constexpr double kPi = 3.14159265358979323846;

// straight_short (60 m Iberian-gauge straight, paper coach at 110 km/h, co-simulation on rigid_fe) ending
// at end_time; track step h = vehicle max step = 2e-5 s (the scene defaults, the paper's values).
core::Scene cosimScene(double end_time) {
  core::Scene scene = core::fixtures::loadConfigScene("straight_short.yaml");
  scene.solver.end.kind = core::EndKind::kTime;
  scene.solver.end.value = end_time;
  return scene;
}

// The whole vehicle shifted laterally by dy (world y on the straight): every suspension force unchanged,
// the wheelsets start off-centre and the creep forces move them back.
Eigen::VectorXd shifted(const VehicleSimulator& sim, double dy) {
  Eigen::VectorXd y = sim.state();
  for (int b = 0; b < sim.model().nBodies(); ++b) y[VehicleModel::positionOffset(b) + 1] += dy;
  return y;
}

// The track side of the test: the rigid-track contact of every wheel (rail_contact's WheelContactModel
// with the rigid provider, built as VehicleSimulator builds its own) evaluated from the received states.
class RigidTrackPeer {
 public:
  RigidTrackPeer(const core::Scene& scene, const std::vector<WheelDefinition>& wheels, cc::FrameTransport& end)
      : track_(core::buildTrackGeometry(scene)),
        model_(makeModel(scene)),
        coupling_(cc::couplingConfig(scene), end),
        work_(wheels.size()),
        result_(wheels.size()) {
    // The frames carry the contact's wheel centre (the taping-line point) directly.
    for (const WheelDefinition& w : wheels) side_.push_back(w.side);
    steps_.reserve(100000);
    times_.reserve(100000);
  }

  // Serves steps until the vehicle closes; ok() false if anything else ended it.
  void run() {
    for (;;) {
      const cc::Result r = coupling_.receive();
      if (r.status == cc::Status::kPeerClosed) return;
      if (!r.ok()) {
        error_ = r.message;
        return;
      }
      const cc::WheelStateFrame& in = coupling_.states();
      steps_.push_back(in.step);
      times_.push_back(in.time);
      cc::WrenchFrame& out = coupling_.wrenches();
      for (std::uint32_t i = 0; i < in.count; ++i) evaluate(in.wheels[i], out.wheels[i]);
      const cc::Result s = coupling_.send();
      if (!s.ok()) {
        error_ = s.message;
        return;
      }
    }
  }

  const std::string& error() const { return error_; }
  const std::vector<std::uint64_t>& steps() const { return steps_; }
  const std::vector<double>& times() const { return times_; }

 private:
  static rc::WheelContactModel makeModel(const core::Scene& scene) {
    rc::WheelContactOptions options = SimulatorSettings().contact;
    options.flange_contact = scene.effects.flange_contact;
    options.spin = scene.effects.spin_creepage;
    options.creep_law = rc::CreepLaw::kPolach;
    const rc::WheelProfile wheel = scene.vehicle.wheel_profile_file.empty()
                                       ? rc::makeS1002()
                                       : rc::loadWheelProfile(scene.vehicle.wheel_profile_file.path);
    return rc::WheelContactModel(wheel, scene.vehicle.nominal_radius, core::railProfileCurve(scene),
                                 Eigen::Vector2d(0.0, -rc::uic60::kCentroidDepth), options);
  }

  void evaluate(const cc::WheelState& in, cc::WheelWrench& out) {
    const std::size_t i = in.id;
    const Eigen::Matrix3d& R = in.R_wheelset_to_world;
    model_.evaluate(in, side_[i], track_, rc::RigidRailDeformation(), work_[i], result_[i]);
    const Eigen::Vector3d& f = result_[i].wheel_centre.force_in_world;
    out.id = in.id;
    out.f_wheel_in_world = f;
    // Eq. 13 moment about the wheel centre, world frame.
    out.n_wheel_in_world = R * result_[i].wheel_centre.moment_in_wheelset;
  }

  rc::TrackGeometry track_;
  rc::WheelContactModel model_;
  cc::TrackCoupling coupling_;
  std::vector<rc::WheelContactWork> work_;
  std::vector<rc::WheelContactResult> result_;
  std::vector<rc::RailSide> side_;
  std::vector<std::uint64_t> steps_;
  std::vector<double> times_;
  std::string error_;
};

// Leading-wheelset record at the sampling instants.
struct Record {
  std::vector<double> t, lateral, vertical, yaw;
  void add(double time, const WheelsetTrackOutput& o) {
    t.push_back(time), lateral.push_back(o.lateral), vertical.push_back(o.vertical), yaw.push_back(o.angle_of_attack);
  }
};

double maxDiff(const std::vector<double>& a, const std::vector<double>& b) {
  double m = 0.0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) m = std::max(m, std::abs(a[i] - b[i]));
  return m;
}
double range(const std::vector<double>& a) {
  if (a.empty()) return 0.0;
  const auto [lo, hi] = std::minmax_element(a.begin(), a.end());
  return *hi - *lo;
}

constexpr double kEnd = 0.3;      // simulated time [s]
constexpr double kSample = 1e-3;  // sampling interval [s]
constexpr double kShift = 2e-3;   // initial lateral offset of the vehicle [m]

TEST(CosimVehicle, ReproducesTheVehicleAloneOnTheRigidTrack) {
  // Standalone: the same scene on the rigid track.
  core::Scene rigid = cosimScene(kEnd);
  rigid.effects.track_model = core::TrackModel::kRigid;
  VehicleSimulator alone(resolveVehicle(rigid));
  alone.resetState(shifted(alone, kShift));
  Record ra;
  const int n_samples = static_cast<int>(std::lround(kEnd / kSample));
  const auto a0 = std::chrono::steady_clock::now();
  for (int j = 1; j <= n_samples; ++j) {
    const RunStatus s = alone.advanceTo(j * kSample);
    ASSERT_TRUE(s == RunStatus::kRunning || s == RunStatus::kFinished) << alone.message();
    ra.add(alone.time(), alone.wheelsets()[0]);
  }
  const double wall_alone = std::chrono::duration<double>(std::chrono::steady_clock::now() - a0).count();

  // Co-simulation over the loopback: vehicle in this thread, rigid-track peer in another.
  const core::Scene scene = cosimScene(kEnd);
  cc::LoopbackLink link(scene.wheelCount());
  CosimVehicle cosim(resolveCosimVehicle(scene), link.vehicleEnd());
  cosim.resetState(shifted(cosim.simulator(), kShift));
  RigidTrackPeer peer(scene, cosim.simulator().contactModel().wheels(), link.trackEnd());
  // The vehicle's own contact evaluations (placement and settling); none may follow: the wrenches must
  // all come from the track side.
  const long long own_evaluations = cosim.simulator().contactData().evaluations;
  const double h = cosim.trackStep();
  const int per_sample = static_cast<int>(std::lround(kSample / h));
  Record rc_;
  const auto c0 = std::chrono::steady_clock::now();
  std::thread track([&peer] { peer.run(); });
  RunStatus s = cosim.start();
  std::uint64_t k = 0;
  while (s == RunStatus::kRunning) {
    s = cosim.step();
    ++k;
    if (k % static_cast<std::uint64_t>(per_sample) == 0 && (s == RunStatus::kRunning || s == RunStatus::kFinished)) {
      rc_.add(cosim.time(), cosim.simulator().wheelsets()[0]);
    }
  }
  cosim.close();
  track.join();
  const double wall_cosim = std::chrono::duration<double>(std::chrono::steady_clock::now() - c0).count();
  ASSERT_EQ(s, RunStatus::kFinished) << cosim.message();
  EXPECT_EQ(peer.error(), "");
  EXPECT_TRUE(cosim.simulator().externalWheelWrenches());
  EXPECT_EQ(cosim.simulator().contactData().evaluations, own_evaluations);

  // Every step exchanged once, in order, at t_k = k h: step 0 (initial states) to the end.
  const std::uint64_t n_steps = static_cast<std::uint64_t>(std::lround(kEnd / h)) + 1;
  ASSERT_EQ(peer.steps().size(), n_steps);
  EXPECT_EQ(cosim.stepsExchanged(), n_steps);
  for (std::size_t i = 0; i < peer.steps().size(); ++i) {
    ASSERT_EQ(peer.steps()[i], i);
    ASSERT_NEAR(peer.times()[i], static_cast<double>(i) * h, 1e-9 * h);
  }
  // The vehicle's internal steps never exceed h (CVODE's max step; 1e-12 relative for rounding).
  EXPECT_GT(cosim.maxInternalStep(), 0.0);
  EXPECT_LE(cosim.maxInternalStep(), h * (1.0 + 1e-12));
  // At least one internal step per track step on average.
  EXPECT_GE(cosim.simulator().counters().steps, static_cast<long>(n_steps - 1));

  // Same samples, leading wheelset.
  ASSERT_EQ(rc_.t.size(), ra.t.size());
  for (std::size_t i = 0; i < ra.t.size(); ++i) ASSERT_NEAR(rc_.t[i], ra.t[i], 1e-12);
  const double d_lat = maxDiff(rc_.lateral, ra.lateral);
  const double d_vert = maxDiff(rc_.vertical, ra.vertical);
  const double d_yaw_deg = maxDiff(rc_.yaw, ra.yaw) * 180.0 / kPi;
  std::printf("leading wheelset alone, %.2f s: range of lateral %.3e m, vertical %.3e m, angle of attack %.3e deg\n",
              kEnd, range(ra.lateral), range(ra.vertical), range(ra.yaw) * 180.0 / kPi);
  std::printf("cosim - alone: lateral %.3e m, vertical %.3e m, angle of attack %.3e deg\n", d_lat, d_vert, d_yaw_deg);
  std::printf("wall: alone %.2f s, cosim %.2f s (%llu exchanges, %ld + %ld steps)\n", wall_alone, wall_cosim,
              static_cast<unsigned long long>(n_steps), alone.counters().steps, cosim.simulator().counters().steps);
  // The motion compared is not trivial: it varies by far more than the deviations allowed below.
  EXPECT_GT(range(ra.lateral), 10.0 * 2.5e-5);
  EXPECT_GT(range(ra.yaw) * 180.0 / kPi, 10.0 * 4.7e-4);
  EXPECT_GT(range(ra.vertical), 10.0 * 8e-8);
  // The paper's deviations between its two rigid runs (section 6).
  EXPECT_LT(d_lat, 2.5e-5);
  EXPECT_LT(d_yaw_deg, 4.7e-4);
  EXPECT_LT(d_vert, 8e-8);
}

// The node builds the vehicle first, sends the handshake the model's wheel span, then connects the
// transport: that run is the run of a vehicle built connected, bit for bit.
TEST(CosimVehicle, BuildingBeforeConnectingGivesTheSameRun) {
  const core::Scene scene = cosimScene(0.02);
  auto runOf = [&scene](bool connect_later, std::vector<double>& lateral) {
    cc::LoopbackLink link(scene.wheelCount());
    std::unique_ptr<CosimVehicle> v;
    if (connect_later) {
      v = std::make_unique<CosimVehicle>(resolveCosimVehicle(scene));
      EXPECT_FALSE(v->connected());
      EXPECT_EQ(v->stepsExchanged(), 0u);
      // What the node sends in the handshake: the span of the model it built, the span of the file.
      EXPECT_EQ(v->simulator().model().wheelSpan(), loadVehicleModel(scene.vehicle.data.path).wheelSpan());
      v->connect(link.vehicleEnd());
      EXPECT_THROW(v->connect(link.vehicleEnd()), std::logic_error);
    } else {
      v = std::make_unique<CosimVehicle>(resolveCosimVehicle(scene), link.vehicleEnd());
    }
    EXPECT_TRUE(v->connected());
    v->resetState(shifted(v->simulator(), kShift));
    RigidTrackPeer peer(scene, v->simulator().contactModel().wheels(), link.trackEnd());
    std::thread track([&peer] { peer.run(); });
    RunStatus s = v->start();
    while (s == RunStatus::kRunning) {
      s = v->step();
      lateral.push_back(v->simulator().wheelsets()[0].lateral);
      lateral.push_back(v->simulator().wheelsets()[0].vertical);
    }
    v->close();
    track.join();
    EXPECT_EQ(s, RunStatus::kFinished) << v->message();
    EXPECT_EQ(peer.error(), "");
  };
  std::vector<double> connected_at_build, connected_later;
  runOf(false, connected_at_build);
  runOf(true, connected_later);
  ASSERT_GT(connected_at_build.size(), 100u);
  EXPECT_EQ(connected_later, connected_at_build);
}

TEST(CosimVehicle, StartBeforeConnectIsRefused) {
  CosimVehicle v(resolveCosimVehicle(cosimScene(0.01)));
  EXPECT_EQ(v.start(), RunStatus::kIntegratorFailed);
  EXPECT_EQ(v.message(), "cosim vehicle: Start() before connect()");
  v.close();  // nothing to tell: no transport
}

TEST(CosimVehicle, ResolvingRefusesAScene) {
  cc::LoopbackLink link(8);
  core::Scene rigid = cosimScene(0.1);
  rigid.effects.track_model = core::TrackModel::kRigid;
  EXPECT_THROW(resolveCosimVehicle(rigid), std::runtime_error);
  core::Scene big_step = cosimScene(0.1);
  big_step.solver.vehicle_max_step = 2.0 * big_step.solver.track_step;
  try {
    CosimVehicle v(resolveCosimVehicle(big_step), link.vehicleEnd());
    ADD_FAILURE() << "a vehicle max step larger than the track step was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("solver.vehicle_max_step"), std::string::npos) << e.what();
  }
}

}  // namespace
// The run loop of the node (VehicleRun): alone, an output at t = 0 and at every n / output.rate to the
// end; co-simulated, at the exchange that reaches each output instant; a raised stop flag ends the run with
// exit 5; a track that closes early is an exchange failure with the exit code of a peer gone (4).
TEST(VehicleRun, AloneOutputsEveryInstantFromTheStartToTheEnd) {
  core::Scene scene = cosimScene(0.02);
  scene.output.rate = 500.0;
  VehicleSimulator sim(resolveVehicle(scene));
  VehicleRun run(rail::core::runSettings(scene), sim);
  int outputs = 0;
  while (run.next() == VehicleRun::Event::kOutput) {
    EXPECT_NEAR(sim.time(), static_cast<double>(run.outputIndex()) / 500.0, 1e-12);
    ++outputs;
  }
  EXPECT_EQ(outputs, 11);  // t = 0, 2, ..., 20 ms
  EXPECT_EQ(run.end(), VehicleRun::End::kFinished);
  EXPECT_EQ(run.exitCode(), core::kExitOk);
  EXPECT_EQ(run.next(), VehicleRun::Event::kEnd);
}

TEST(VehicleRun, TheStopFlagEndsTheRunWithExit5) {
  core::Scene scene = cosimScene(0.02);
  scene.output.rate = 500.0;
  VehicleSimulator sim(resolveVehicle(scene));
  std::atomic<bool> stop{false};
  VehicleRun run(rail::core::runSettings(scene), sim, {&stop, nullptr});
  int outputs = 0;
  while (run.next() == VehicleRun::Event::kOutput) {
    if (++outputs == 3) stop = true;
  }
  EXPECT_EQ(outputs, 3);
  EXPECT_EQ(run.end(), VehicleRun::End::kStopped);
  EXPECT_EQ(run.exitCode(), core::kExitInterrupted);
  EXPECT_NEAR(sim.time(), 0.004, 1e-12);
}

TEST(VehicleRun, CosimulatedOutputsAtTheExchangeThatReachesEachInstant) {
  core::Scene scene = cosimScene(0.004);
  scene.output.rate = 1000.0;
  cc::LoopbackLink link(scene.wheelCount());
  CosimVehicle cosim(resolveCosimVehicle(scene), link.vehicleEnd());
  RigidTrackPeer peer(scene, cosim.simulator().contactModel().wheels(), link.trackEnd());
  std::thread track([&peer] { peer.run(); });
  VehicleRun run(rail::core::runSettings(scene), cosim);
  std::vector<double> times;
  while (run.next() == VehicleRun::Event::kOutput) times.push_back(cosim.time());
  cosim.close();
  track.join();
  EXPECT_EQ(run.end(), VehicleRun::End::kFinished) << run.message();
  ASSERT_EQ(times.size(), 5u);  // t = 0, 1, 2, 3, 4 ms: steps 0, 50, ..., 200 of 2e-5 s
  for (std::size_t i = 0; i < times.size(); ++i) EXPECT_NEAR(times[i], 1e-3 * static_cast<double>(i), 1e-12);
  EXPECT_EQ(cosim.stepsExchanged(), 201u);
}

// The exchanges' checks evaluate positions only and the steps that reach an output instant complete the
// outputs (floor accelerations, energy, wheels) before their exchange: the same values, to the last bit,
// as a run that evaluates everything at every exchange (the same arithmetic at the same states).
struct OutputRecord {
  double t = 0.0;
  std::vector<MeasurementOutput> measurements;
  EnergyOutput energy;
  std::vector<WheelOutput> wheels;
};

// The coach's data file with a measurement point on the leading wheelset as well: its acceleration carries
// the wheel wrenches, so it tells the wrenches a step integrated with from those of the next exchange.
std::string coachWithWheelsetPoint(const std::string& coach) {
  std::ifstream in(coach);
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::string key = "measurement_points:\n";
  const std::size_t at = yaml.find(key);
  if (at == std::string::npos) throw std::runtime_error(coach + ": no measurement_points");
  yaml.insert(at + key.size(), "  - {name: axle_front, body: ws1, position: [22.35, 0.0, 0.445]}\n");
  const std::string path = ::testing::TempDir() + "coach_with_wheelset_point.yaml";
  std::ofstream(path) << yaml;
  return path;
}

std::vector<OutputRecord> cosimOutputs(bool every_exchange) {
  core::Scene scene = cosimScene(0.004);
  scene.output.rate = 1000.0;
  scene.vehicle.data.path = coachWithWheelsetPoint(scene.vehicle.data.path);
  scene.effects.floor_acceleration_output = true;
  scene.effects.energy_output = true;
  cc::LoopbackLink link(scene.wheelCount());
  CosimVehicle cosim(resolveCosimVehicle(scene), link.vehicleEnd());
  RigidTrackPeer peer(scene, cosim.simulator().contactModel().wheels(), link.trackEnd());
  std::thread track([&peer] { peer.run(); });
  const VehicleSimulator& sim = cosim.simulator();
  std::vector<OutputRecord> out;
  auto record = [&] { out.push_back({cosim.time(), sim.measurements(), sim.energy(), sim.wheels()}); };
  if (every_exchange) {
    // Every step an output step: the full evaluation at each exchange, recorded at the output instants.
    RunStatus s = cosim.start();
    record();
    for (int k = 1; k <= 200 && s == RunStatus::kRunning; ++k) {
      s = cosim.step(0.0);
      if (k % 50 == 0) record();
    }
  } else {
    VehicleRun run(rail::core::runSettings(scene), cosim);
    while (run.next() == VehicleRun::Event::kOutput) record();
    EXPECT_EQ(run.end(), VehicleRun::End::kFinished) << run.message();
  }
  cosim.close();
  track.join();
  return out;
}

TEST(VehicleRun, CosimulatedOutputsEqualAFullEvaluationAtEveryExchange) {
  const std::vector<OutputRecord> lazy = cosimOutputs(false), full = cosimOutputs(true);
  ASSERT_EQ(lazy.size(), 5u);
  ASSERT_EQ(full.size(), lazy.size());
  ASSERT_EQ(lazy[1].measurements.size(), 4u);
  for (std::size_t k = 0; k < lazy.size(); ++k) {
    EXPECT_NEAR(lazy[k].t, full[k].t, 1e-12);
    for (std::size_t m = 0; m < lazy[k].measurements.size(); ++m)
      EXPECT_EQ(lazy[k].measurements[m].specific_force_in_body, full[k].measurements[m].specific_force_in_body)
          << "output " << k << ", point " << m;
    EXPECT_EQ(lazy[k].energy.kinetic, full[k].energy.kinetic) << "output " << k;
    EXPECT_EQ(lazy[k].energy.potential, full[k].energy.potential) << "output " << k;
    for (std::size_t i = 0; i < lazy[k].wheels.size(); ++i) {
      EXPECT_EQ(lazy[k].wheels[i].p_in_world, full[k].wheels[i].p_in_world) << "output " << k << ", wheel " << i;
      EXPECT_EQ(lazy[k].wheels[i].force_in_world, full[k].wheels[i].force_in_world)
          << "output " << k << ", wheel " << i;
    }
  }
  EXPECT_GT(lazy[4].energy.kinetic, 0.0);
  EXPECT_GT(lazy[4].measurements[0].specific_force_in_body.norm(), 9.0);  // gravity's reading, about 9.81
}

TEST(VehicleRun, ATrackThatClosesEarlyIsAnExchangeFailure) {
  const core::Scene scene = cosimScene(0.004);
  cc::LoopbackLink link(scene.wheelCount());
  CosimVehicle cosim(resolveCosimVehicle(scene), link.vehicleEnd());
  // The track answers 10 steps with zero wrenches, then closes.
  std::thread track([&] {
    cc::TrackCoupling coupling(cc::couplingConfig(scene), link.trackEnd());
    for (int k = 0; k < 10; ++k) {
      if (!coupling.receive()) break;
      for (std::uint32_t i = 0; i < coupling.states().count; ++i) coupling.wrenches().wheels[i].id = i;
      if (!coupling.send()) break;
    }
    coupling.close();
  });
  VehicleRun run(rail::core::runSettings(scene), cosim);
  while (run.next() == VehicleRun::Event::kOutput) {
  }
  cosim.close();
  track.join();
  EXPECT_EQ(run.end(), VehicleRun::End::kExchangeFailed);
  EXPECT_EQ(run.exitCode(), core::kExitPeerTimeout);
  EXPECT_EQ(run.message().rfind("exchange with the track node failed at step ", 0), 0u) << run.message();
}

TEST(VehicleRun, ExitCodesOfTheRunsEnds) {
  EXPECT_EQ(exitCodeOf(RunStatus::kFinished), core::kExitOk);
  EXPECT_EQ(exitCodeOf(RunStatus::kDerailed), core::kExitDerailed);
  EXPECT_EQ(exitCodeOf(RunStatus::kLeftTrack), core::kExitDerailed);
  EXPECT_EQ(exitCodeOf(RunStatus::kNonFinite), core::kExitNumerical);
  EXPECT_EQ(exitCodeOf(RunStatus::kIntegratorFailed), core::kExitNumerical);
  EXPECT_STREQ(toString(RunStatus::kDerailed), "derailed");
}

}  // namespace rail::vehicle
