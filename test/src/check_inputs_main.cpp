// railsim_check_inputs: loads a scene and builds and briefly runs everything a run of it would build,
// without ROS, to check that an input is either used correctly or refused with a message naming the file.
//
//   railsim_check_inputs <scene.yaml> [--set key=value ...] [--steps N] [--vehicle-time T]
//
// What is built (the nodes' ROS-free part, src/rail_vehicle_node/src/node/vehicle_node.cpp and
// src/rail_track_node/src/node/track_node.cpp):
//  - always: the track geometry (rail_core buildTrackGeometry: segments, irregularities, rail profile)
//    and the rail profile curve; sampled along the track and the profile;
//  - a vehicle: the VehicleSimulator (vehicle data file, wheel profile, contact, settling on the rigid track),
//    advanced on the rigid track for T seconds of simulated time (default 2 ms, --vehicle-time);
//  - track_model rigid_fe / flexible, or no vehicle: the scene's FE track (buildSceneTrack: track data file,
//    mesh, M, C, K), its static equilibrium and N Newmark steps of the TrackSimulator (default 20, --steps)
//    under the scene's moving loads (none with a vehicle), with the scene's rail deflection sections;
//  - a co-simulation (vehicle and rigid_fe / flexible): the track side (CosimTrack, with its moving window
//    when the scene asks for one) stepped N times with the vehicle's wheel states at t_k = k h
//    (h = solver.track_step) and the vehicle integrated alone between them.
// Every state, force and deflection read back is checked finite.
//
// Exit codes and the one line printed:
//   0  "ok: <summary>" (stdout)
//   1  "error: <message>" (stderr): the input was refused (a std::exception from a loader or builder; its
//      message names the file and the field or line)
//   2  "error: non-finite <what> in <file>" (stderr): a result was NaN or Inf (a defect)
//   3  "error: run stopped: <why>" (stderr): the vehicle integration failed on an accepted input (a defect)
//   4  "error: usage: ..." (stderr): bad command line
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <rail_contact/profile.hpp>
#include <rail_contact/track_geometry.hpp>
#include <rail_core/coupling/frames.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/scene.hpp>
#include <rail_core/scene_loader.hpp>
#include <rail_track_node/cosim_track.hpp>
#include <rail_track_node/scene_track.hpp>
#include <rail_track_node/track_simulator.hpp>
#include <rail_vehicle_node/vehicle_simulator.hpp>

namespace {

namespace rc = rail::contact;
namespace rt = rail::track;
namespace rv = rail::vehicle;
namespace cc = rail::core::coupling;
using rail::core::Scene;

constexpr int kExitOk = 0;
constexpr int kExitRefused = 1;
constexpr int kExitNonFinite = 2;
constexpr int kExitRunFailed = 3;
constexpr int kExitUsage = 4;

// A result that is NaN or Inf: what it is and the file whose data produced it.
struct NonFinite {
  std::string what;
  std::string file;
};

// A vehicle run that stopped on an accepted input (integrator failure, non-finite state).
struct RunFailed {
  std::string why;
};

template <typename Derived>
void requireFinite(const Eigen::DenseBase<Derived>& v, const std::string& what, const std::string& file) {
  if (!v.derived().allFinite()) throw NonFinite{what, file};
}
void requireFinite(double v, const std::string& what, const std::string& file) {
  if (!std::isfinite(v)) throw NonFinite{what, file};
}

// The file a vehicle result comes from: the vehicle data file, or the scene when it has none.
std::string vehicleFile(const Scene& scene) {
  return scene.vehicle.data.empty() ? scene.file : scene.vehicle.data.path;
}
std::string trackDataFile(const Scene& scene) { return scene.track.data.empty() ? scene.file : scene.track.data.path; }

// Samples the centre line and both rails at 101 points and the rail profile at 101 points.
void checkGeometry(const Scene& scene, const rc::TrackGeometry& geometry, const rc::ProfileCurve& rail) {
  rc::TrackPoint tp;
  rc::RailPoint rp;
  const double s0 = geometry.sStart(), s1 = geometry.sEnd();
  requireFinite(s0, "track geometry start arc length", scene.file);
  requireFinite(s1, "track geometry end arc length", scene.file);
  for (int i = 0; i <= 100; ++i) {
    const double s = s0 + (s1 - s0) * i / 100.0;
    geometry.centre(s, tp);
    requireFinite(tp.p_center_in_world, "track centre line", scene.file);
    requireFinite(tp.R_track_to_world, "track frame", scene.file);
    for (rc::RailSide side : {rc::RailSide::kLeft, rc::RailSide::kRight}) {
      geometry.rail(side, s, rp);
      requireFinite(rp.p_origin_in_world, "rail origin", scene.file);
      requireFinite(rp.R_rail_to_world, "rail frame", scene.file);
    }
  }
  const std::string profile_file =
      scene.track.rail_profile_file.empty() ? scene.file : scene.track.rail_profile_file.path;
  requireFinite(rail.uMax(), "rail profile length", profile_file);
  for (int i = 0; i <= 100; ++i) {
    const double u = rail.uMax() * i / 100.0;
    requireFinite(rail.position(u), "rail profile point", profile_file);
    requireFinite(rail.normal(u), "rail profile normal", profile_file);
  }
}

void checkVehicleOutputs(const Scene& scene, rv::VehicleSimulator& sim) {
  const std::string file = vehicleFile(scene);
  sim.updateOutputs();
  requireFinite(sim.state(), "vehicle state", file);
  requireFinite(sim.time(), "vehicle time", file);
  for (const rv::WheelOutput& w : sim.wheels()) {
    requireFinite(w.p_in_world, "wheel centre position", file);
    requireFinite(w.v_in_world, "wheel centre velocity", file);
    requireFinite(w.omega_in_world, "wheelset angular velocity", file);
    requireFinite(w.force_in_world, "wheel contact force", file);
    requireFinite(w.moment_in_world, "wheel contact moment", file);
    requireFinite(w.arc_length, "wheel arc length", file);
  }
  for (const rv::WheelsetTrackOutput& o : sim.wheelsets()) {
    requireFinite(Eigen::Vector4d(o.lateral, o.vertical, o.angle_of_attack, o.roll), "wheelset kinematics", file);
  }
}

// Wheel states of the vehicle's wheels as the co-simulation frame of step k.
void fillFrame(const rv::VehicleSimulator& sim, std::uint64_t k, double h, std::uint64_t hash,
               cc::WheelStateFrame& frame) {
  frame.step = k;
  frame.time = static_cast<double>(k) * h;
  frame.scene_hash = hash;
  frame.count = static_cast<std::uint32_t>(sim.wheels().size());
  for (std::size_t i = 0; i < sim.wheels().size(); ++i) {
    const rv::WheelOutput& w = sim.wheels()[i];
    cc::WheelState& s = frame.wheels[i];
    s.id = static_cast<std::uint32_t>(w.wheel_id);
    s.arc_length = w.arc_length;
    s.p_wheel_in_world = w.p_in_world;
    s.R_wheelset_to_world = Eigen::Quaterniond(w.orientation[0], w.orientation[1], w.orientation[2], w.orientation[3])
                                .normalized()
                                .toRotationMatrix();
    s.v_wheel_in_world = w.v_in_world;
    s.omega_wheelset_in_world = w.omega_in_world;
  }
}

// Advances the vehicle to t; a run that stops for another reason than its end or a derailment/leaving the
// track (outcomes of the physics, reported in the summary) is a failure.
rv::RunStatus advance(rv::VehicleSimulator& sim, double t) {
  const rv::RunStatus st = sim.advanceTo(t);
  if (st == rv::RunStatus::kNonFinite) throw RunFailed{"non-finite vehicle state: " + sim.message()};
  if (st == rv::RunStatus::kIntegratorFailed) throw RunFailed{"vehicle integrator failed: " + sim.message()};
  return st;
}

const char* statusName(rv::RunStatus s) {
  switch (s) {
    case rv::RunStatus::kRunning:
      return "running";
    case rv::RunStatus::kFinished:
      return "finished";
    case rv::RunStatus::kDerailed:
      return "derailed";
    case rv::RunStatus::kNonFinite:
      return "non-finite";
    case rv::RunStatus::kLeftTrack:
      return "left the track";
    case rv::RunStatus::kIntegratorFailed:
      return "integrator failed";
  }
  return "?";
}

// Builds and runs everything; returns the summary.
std::string check(const std::string& path, const rail::core::SceneOverrides& overrides, int steps,
                  double vehicle_time) {
  std::ostringstream summary;
  const Scene scene = rail::core::loadSceneFile(path, overrides);
  summary << "scene " << scene.name << " (" << rail::core::toString(scene.effects.track_model) << ")";

  // Track geometry and rail profile (both nodes build them).
  const rc::TrackGeometry geometry = rail::core::buildTrackGeometry(scene);
  const rc::ProfileCurve rail_profile = rail::core::railProfileCurve(scene);
  checkGeometry(scene, geometry, rail_profile);
  summary << "; track " << geometry.sEnd() - geometry.sStart() << " m";

  // Vehicle on the rigid track.
  std::unique_ptr<rv::VehicleSimulator> vehicle;
  rv::RunStatus vehicle_status = rv::RunStatus::kRunning;
  if (scene.has_vehicle) {
    vehicle = std::make_unique<rv::VehicleSimulator>(rv::resolveVehicle(scene));
    checkVehicleOutputs(scene, *vehicle);
    requireFinite(vehicle->settleLift(), "vehicle settling lift", vehicleFile(scene));
  }

  // FE track under the moving loads (or its own weight) with the scene's deflection sections.
  long fe_dofs = 0, fe_steps = 0;
  const bool fe_track = scene.needsTrackNode() || !scene.has_vehicle;
  if (fe_track) {
    rt::SceneTrack track = rt::buildSceneTrack(scene);
    rt::SimulatorSettings settings;
    settings.track_step = scene.solver.track_step;
    if (!scene.has_vehicle) {
      const double t_end = rt::movingLoadEndTime(scene);
      requireFinite(t_end, "moving-load end time", scene.file);
      settings.loads = scene.moving_loads;
    }
    settings.t_end = steps * settings.track_step;
    settings.rail_height = track.rail_height;
    rt::TrackSimulator sim(track.model, settings);
    const std::string file = trackDataFile(scene);
    const bool deflections = scene.effects.rail_deflection_output && !scene.output.deflection_sections.empty();
    if (deflections) {
      const rt::TrackFrameFunction frames = rt::seatPlaneFrames(track.geometry, track.seat_below_centre);
      for (std::size_t i = 0; i < scene.output.deflection_sections.size(); ++i) {
        try {
          sim.addSection(scene.output.deflection_sections[i], frames);
        } catch (const std::exception& e) {  // the track node's message for this key
          throw std::runtime_error(scene.file + ": output.deflection_sections[" + std::to_string(i) + "]: " + e.what());
        }
      }
    }
    requireFinite(sim.state().d, "track static displacement", file);
    rt::RailSectionDeflection deflection;
    for (int k = 1; k <= steps; ++k) {
      sim.advanceTo(k * settings.track_step);
      requireFinite(sim.state().d, "track displacement", file);
      requireFinite(sim.state().v, "track velocity", file);
      requireFinite(sim.state().a, "track acceleration", file);
      for (int i = 0; i < sim.sectionCount(); ++i) {
        sim.sectionDeflection(i, deflection);
        for (int r = 0; r < 2; ++r) {
          requireFinite(deflection.displacement[r], "rail deflection", file);
          requireFinite(deflection.rotation[r], "rail rotation", file);
        }
      }
    }
    fe_dofs = track.model.system.size();
    fe_steps = sim.steps();
    summary << "; FE track " << fe_dofs << " DOFs, " << fe_steps << " Newmark steps of " << settings.track_step << " s";
  }

  // Co-simulation: the track side fed with the vehicle's wheel states.
  if (scene.cosimulation()) {
    rt::CosimTrackOptions track_options;
    track_options.window.vehicle_length = vehicle->model().wheelSpan();  // as the handshake carries it
    rt::CosimTrack track(rt::resolveCosimTrack(scene), track_options);
    const bool deflections = scene.effects.rail_deflection_output && !scene.output.deflection_sections.empty();
    if (deflections) {
      for (std::size_t i = 0; i < scene.output.deflection_sections.size(); ++i) {
        try {
          track.addSection(scene.output.deflection_sections[i]);
        } catch (const std::exception& e) {  // the track node's message for this key
          throw std::runtime_error(scene.file + ": output.deflection_sections[" + std::to_string(i) + "]: " + e.what());
        }
      }
    }
    const int n = track.wheelCount();
    cc::WheelStateFrame states(n);
    cc::WrenchFrame wrenches(n);
    const double h = scene.solver.track_step;
    const std::string file = trackDataFile(scene);
    rt::RailSectionDeflection deflection;
    int k = 0;
    for (; k <= steps; ++k) {
      if (k > 0) {
        vehicle_status = advance(*vehicle, k * h);
        if (vehicle_status != rv::RunStatus::kRunning) break;
      }
      checkVehicleOutputs(scene, *vehicle);
      fillFrame(*vehicle, static_cast<std::uint64_t>(k), h, scene.hash, states);
      const rt::CosimStepStatus st = track.step(states, wrenches);
      if (st != rt::CosimStepStatus::kOk) {
        throw RunFailed{"co-simulation track step " + std::to_string(k) + " refused the vehicle's frame (status " +
                        std::to_string(static_cast<int>(st)) + ")"};
      }
      for (std::uint32_t i = 0; i < wrenches.count; ++i) {
        requireFinite(wrenches.wheels[i].f_wheel_in_world, "co-simulation wheel force", file);
        requireFinite(wrenches.wheels[i].n_wheel_in_world, "co-simulation wheel moment", file);
      }
      if (const rt::NewmarkState* s = track.state()) {
        requireFinite(s->d, "co-simulation track displacement", file);
        requireFinite(s->v, "co-simulation track velocity", file);
      }
      for (int i = 0; i < track.sectionCount(); ++i) {
        track.sectionDeflection(i, deflection);
        for (int r = 0; r < 2; ++r) requireFinite(deflection.displacement[r], "co-simulation rail deflection", file);
      }
    }
    summary << "; co-simulation track " << (track.flexible() ? "flexible" : "rigid") << " "
            << (track.trackWindow() != nullptr ? "windowed " : "") << track.framesStepped() << " frames, "
            << track.newmarkSteps() << " Newmark steps";
  }

  // The vehicle alone for the rest of its time.
  if (vehicle) {
    const double t_end = std::max(vehicle_time, vehicle->time());
    const double dt_out = 5e-4;  // outputs checked every 0.5 ms
    for (double t = vehicle->time() + dt_out; vehicle_status == rv::RunStatus::kRunning; t += dt_out) {
      vehicle_status = advance(*vehicle, std::min(t, t_end));
      checkVehicleOutputs(scene, *vehicle);
      if (t >= t_end) break;
    }
    const rv::IntegratorCounters c = vehicle->counters();
    summary << "; vehicle " << vehicle->model().nBodies() << " bodies, " << vehicle->wheels().size()
            << " wheels, settled " << vehicle->settleLift() * 1e3 << " mm, t = " << vehicle->time() << " s ("
            << statusName(vehicle_status) << "), " << c.steps << " CVODE steps";
  }
  return summary.str();
}

int usage(const char* msg) {
  std::cerr << "error: usage: " << msg
            << "\n  railsim_check_inputs <scene.yaml> [--set key=value ...] [--steps N] [--vehicle-time T]\n";
  return kExitUsage;
}

}  // namespace

int main(int argc, char** argv) {
  const char* path = nullptr;
  rail::core::SceneOverrides overrides;
  int steps = 20;
  double vehicle_time = 2e-3;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--set" || a == "--steps" || a == "--vehicle-time") {
      if (i + 1 >= argc) return usage((a + " needs a value").c_str());
      const char* v = argv[++i];
      if (a == "--set") {
        overrides.push_back(v);
      } else {
        char* end = nullptr;
        const double x = std::strtod(v, &end);
        if (end == v || *end != '\0' || !(x >= 0.0) || !std::isfinite(x))
          return usage((a + ": not a number >= 0").c_str());
        if (a == "--steps")
          steps = static_cast<int>(x);
        else
          vehicle_time = x;
      }
    } else if (a == "-h" || a == "--help") {
      std::cout << "usage: railsim_check_inputs <scene.yaml> [--set key=value ...] [--steps N] [--vehicle-time T]\n";
      return kExitOk;
    } else if (path == nullptr) {
      path = argv[i];
    } else {
      return usage(("unexpected argument '" + a + "'").c_str());
    }
  }
  if (path == nullptr) return usage("no scene file");
  try {
    const std::string summary = check(path, overrides, steps, vehicle_time);
    std::cout << "ok: " << summary << std::endl;
    return kExitOk;
  } catch (const NonFinite& e) {
    std::cerr << "error: non-finite " << e.what << " in " << e.file << std::endl;
    return kExitNonFinite;
  } catch (const RunFailed& e) {
    std::cerr << "error: run stopped: " << e.why << std::endl;
    return kExitRunFailed;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << std::endl;
    return kExitRefused;
  }
}
