// Standalone track under moving loads (see track_simulator.hpp).
#include "rail_track_node/track_simulator.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <sstream>
#include <stdexcept>

#include <rail_contact/beam_shape.hpp>

#include "rail_track_node/elements.hpp"

namespace rail {
namespace track {

namespace {

using Clock = std::chrono::steady_clock;

// Steps between two looks at the wall clock (progress reports).
constexpr long kClockCheckEvery = 128;

double sideSign(int rail) { return rail == kLeftRail ? 1.0 : -1.0; }

int loadCapacity(const rail::core::MovingLoads& loads) {
  // addRailPointLoad adds 12 entries per rail.
  return 24 * static_cast<int>(loads.loads.size()) + 1;
}

}  // namespace

TrackSimulator::TrackSimulator(const TrackModel& model, const SimulatorSettings& settings)
    : model_(model),
      settings_(settings),
      integrator_(model.system, settings.track_step, settings.include_gravity, settings.cost,
                  countEndDashpots(model.mesh)),
      hanging_(model.mesh),
      loads_(loadCapacity(settings.loads) + hanging_.loadCapacity()) {
  if (!(settings.t_end >= 0.0) || !std::isfinite(settings.t_end)) {
    std::ostringstream os;
    os << "TrackSimulator: end time must be finite and >= 0, got " << settings.t_end;
    throw std::runtime_error(os.str());
  }
  head_arm_ = settings.rail_height - model.data.layout.rail_centroid_height;
  end_steps_ = std::lround(settings.t_end / settings.track_step);

  // Static equilibrium under gravity and the loads at t = 0.
  loadsAt(0.0, loads_);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(model.system.size());
  if (settings.include_gravity) f += model.system.f_gravity;
  for (int k = 0; k < loads_.size(); ++k) f(loads_.index(k)) += loads_.value(k);
  if (hanging_.empty()) {
    state_ = integrator_.initialState(solveStatic(model.system, f), &loads_);
  } else {
    const Eigen::VectorXd d0 = hanging_.solveStatic(model.system, f);
    hanging_.addLoads(d0, Eigen::VectorXd::Zero(d0.size()), nullptr, 0.0, loads_);
    state_ = integrator_.initialState(d0, &loads_);
  }
  wall_start_ = last_report_ = Clock::now();
}

void TrackSimulator::setProgressCallback(ProgressCallback cb, double interval_s) {
  progress_ = std::move(cb);
  progress_interval_ = interval_s;
}

bool addRailHeadLoad(const TrackMesh& mesh, double inclination, double head_arm, int rail, double s, double vertical,
                     double lateral, NodalLoads& loads) {
  int beam = 0;
  double xi = 0.0;
  if (!mesh.locateRail(rail, s, beam, xi)) return false;
  // Track axes from the rail beam's axes: the rail frame is the track frame turned by sign * inclination
  // about the tangent (track_mesh.cpp), so b = sign sin(i) y_rail + cos(i) z_rail and
  // n = cos(i) y_rail - sign sin(i) z_rail.
  const Eigen::Matrix3d& R = mesh.beams[beam].R_local_to_world;
  const double sg = sideSign(rail), si = std::sin(inclination), ci = std::cos(inclination);
  const Eigen::Vector3d b = sg * si * R.col(1) + ci * R.col(2);
  const Eigen::Vector3d n = ci * R.col(1) - sg * si * R.col(2);
  const Eigen::Vector3d f = -vertical * b + (sg * lateral) * n;
  const Eigen::Vector3d m = (head_arm * R.col(2)).cross(f);
  return addRailPointLoad(mesh, rail, s, f, m, loads);
}

void TrackSimulator::loadsAt(double t, NodalLoads& loads) const {
  loads.clear();
  const rail::core::MovingLoads& ml = settings_.loads;
  const TrackMesh& mesh = model_.mesh;
  const double incl = model_.data.layout.rail_inclination;
  for (const rail::core::MovingLoad& load : ml.loads) {
    const double s = ml.start_arc_length + ml.speed * t - load.offset;
    for (int r = 0; r < 2; ++r) {
      if (load.rail == rail::core::LoadRail::kLeft && r != kLeftRail) continue;
      if (load.rail == rail::core::LoadRail::kRight && r != kRightRail) continue;
      addRailHeadLoad(mesh, incl, head_arm_, r, s, load.vertical, load.lateral, loads);
    }
  }
}

void TrackSimulator::advanceTo(double t) {
  long target = std::lround(t / settings_.track_step);
  if (target > end_steps_) target = end_steps_;
  while (steps_ < target) {
    const double t_next = static_cast<double>(steps_ + 1) * settings_.track_step;
    loadsAt(t_next, loads_);
    hanging_.addLoads(state_.d, state_.v, nullptr, settings_.track_step, loads_);
    integrator_.step(state_, loads_);
    ++steps_;
    if (progress_ && steps_ % kClockCheckEvery == 0) {
      const Clock::time_point now = Clock::now();
      if (std::chrono::duration<double>(now - last_report_).count() >= progress_interval_) {
        last_report_ = now;
        reportProgress();
      }
    }
  }
  if (progress_ && steps_ == end_steps_ && steps_ > steps_at_start_) {
    reportProgress();
    steps_at_start_ = steps_;  // reported once
  }
}

void TrackSimulator::reportProgress() {
  SimulationProgress p;
  p.t = time();
  p.t_end = settings_.t_end;
  p.steps = steps_;
  p.percent = settings_.t_end > 0.0 ? 100.0 * p.t / settings_.t_end : 100.0;
  const double wall = std::chrono::duration<double>(Clock::now() - wall_start_).count();
  p.real_time_factor = wall > 0.0 ? p.t / wall : 0.0;
  p.eta = p.real_time_factor > 0.0 ? (settings_.t_end - p.t) / p.real_time_factor : 0.0;
  progress_(p);
}

int TrackSimulator::addSection(double s, const TrackFrameFunction& frames) {
  const TrackMesh& mesh = model_.mesh;
  Section sec;
  sec.arc_length = s;
  const Eigen::Matrix3d R_track_to_world = frames(s).R_track_to_world;
  requireOnMeshRails(mesh, s);
  makeRailProbes(mesh, R_track_to_world, s, sec.rail);
  sections_.push_back(sec);
  return static_cast<int>(sections_.size()) - 1;
}

void TrackSimulator::sectionDeflection(int i, const Eigen::VectorXd& d, RailSectionDeflection& out) const {
  rail::core::CostClock::Scope timing(settings_.cost, rail::core::CostClock::kRailDeflection);
  const Section& sec = sections_[i];
  out.arc_length = sec.arc_length;
  evalRailProbes(sec.rail, d, out);
}

double movingLoadEndTime(const rail::core::Scene& scene) {
  const rail::core::End& end = scene.solver.end;
  if (end.kind == rail::core::EndKind::kTime) return end.value;
  const rail::core::MovingLoads& ml = scene.moving_loads;
  if (!(ml.speed > 0.0))
    throw std::runtime_error(scene.file + ": solver.end: an arc-length end needs moving_loads.speed > 0");
  return (end.value - ml.start_arc_length) / ml.speed;
}

}  // namespace track
}  // namespace rail
