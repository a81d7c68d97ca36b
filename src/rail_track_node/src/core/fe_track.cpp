// The full-length FE track of a co-simulation (see fe_track.hpp).
#include "rail_track_node/fe_track.hpp"

#include <sstream>
#include <stdexcept>
#include <utility>

#include <rail_core/scene_loader.hpp>

namespace rail {
namespace track {

FullLengthTrack::FullLengthTrack(TrackLine line, const FullLengthTrackSettings& settings)
    : track_(buildSceneTrack(std::move(line))) {
  if (const std::string why = rail::core::trackStepRule(settings.track_step); !why.empty())
    throw std::runtime_error("FullLengthTrackSettings::track_step " + why);
  const LinearSystem& sys = track_.model.system;
  integrator_ = std::make_unique<NewmarkIntegrator>(sys, settings.track_step, settings.include_gravity, settings.cost,
                                                    countEndDashpots(track_.model.mesh), settings.factor_layout);
  // The start: the static equilibrium under the track's own weight; with hanging sleepers that of the
  // piecewise-linear track (HangingSupports), whose loads at rest then enter the initial accelerations.
  auto hanging = std::make_unique<HangingSupports>(track_.model.mesh);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(sys.size());
  const Eigen::VectorXd& f = settings.include_gravity ? sys.f_gravity : zero;
  if (hanging->empty()) {
    d_static_ = settings.include_gravity ? staticGravityDeflection(sys) : zero;
    state_ = integrator_->initialState(d_static_);
  } else {
    hanging_ = std::move(hanging);
    d_static_ = hanging_->solveStatic(sys, f);
    NodalLoads at_rest(hanging_->loadCapacity());
    hanging_->addLoads(d_static_, zero, nullptr, 0.0, at_rest);
    state_ = integrator_->initialState(d_static_, &at_rest);
  }
  energy_scratch_.resize(sys.size());
  energy_dd_.resize(sys.size());
}

int FullLengthTrack::addSection(double s) {
  Section sec;
  sec.arc_length = s;
  requireOnMeshRails(track_.model.mesh, s);
  rail::contact::TrackPoint tp;
  track_.geometry.centre(s, tp);
  makeRailProbes(track_.model.mesh, tp.R_track_to_world, s, sec.rail);
  sections_.push_back(sec);
  return static_cast<int>(sections_.size()) - 1;
}

void FullLengthTrack::sectionDeflection(int i, RailSectionDeflection& out) const {
  sectionDeflection(i, state_.d, out);
}

void FullLengthTrack::sectionDeflection(int i, const Eigen::VectorXd& d, RailSectionDeflection& out) const {
  const Section& sec = sections_[static_cast<std::size_t>(i)];
  out.arc_length = sec.arc_length;
  evalRailProbes(sec.rail, d, out);
}

void FullLengthTrack::energy(double& kinetic, double& potential) const {
  const LinearSystem& sys = track_.model.system;
  energy_scratch_.noalias() = sys.M * state_.v;
  kinetic = 0.5 * state_.v.dot(energy_scratch_);
  energy_dd_ = state_.d - d_static_;
  energy_scratch_.noalias() = sys.K * energy_dd_;
  potential = 0.5 * energy_dd_.dot(energy_scratch_);
}

}  // namespace track
}  // namespace rail
