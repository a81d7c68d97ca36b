#include "rail_vehicle_node/wheel_rail_contact.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace rail::vehicle {

WheelRailContactModel::WheelRailContactModel(const contact::TrackGeometry& track,
                                             const contact::WheelProfile& wheel_profile, double nominal_radius,
                                             const contact::ProfileCurve& rail_profile,
                                             const Eigen::Vector2d& rail_section_centre_yz,
                                             const contact::WheelContactOptions& options,
                                             std::vector<WheelDefinition> wheels)
    : track_(&track),
      wheel_model_(wheel_profile, nominal_radius, rail_profile, rail_section_centre_yz, options),
      wheels_(std::move(wheels)) {
  if (wheels_.empty()) throw std::runtime_error("wheel-rail contact: the vehicle has no wheels");
}

WheelRailContactData::WheelRailContactData(const WheelRailContactModel& model) {
  const auto n = static_cast<std::size_t>(model.nWheels());
  work.assign(n, contact::WheelContactWork());
  result.assign(n, contact::WheelContactResult());
  s_hint.assign(n, 0.0);
  force_in_world.assign(n, Vector3::Zero());
  moment_in_world.assign(n, Vector3::Zero());
  forEachSaved([](auto& live, auto& saved) { saved = live; });  // sizes the copies once
}

void WheelRailContactData::setExactGaps(bool exact) {
  for (auto& w : work) {
    for (auto& d : w.detection) d.skip_far_searches = !exact;
  }
}

void evaluateWheel(const WheelRailContactModel& model, const VehicleData& data, int k,
                   WheelRailContactData& cd) noexcept {
  const auto i = static_cast<std::size_t>(k);
  const WheelDefinition& w = model.wheels()[i];
  const BodyKinematics& b = data.bodies[static_cast<std::size_t>(w.body)];
  const Vector3 arm_taping = b.A * w.s_taping_in_body;
  contact::WheelState state;
  state.p_wheel_in_world = b.r + arm_taping;
  state.R_wheelset_to_world = b.A;
  state.v_wheel_in_world = b.r_dot + b.omega_world.cross(arm_taping);
  state.omega_wheelset_in_world = b.omega_world;
  state.arc_length = cd.s_hint[i];
  contact::WheelContactResult& out = cd.result[i];
  model.wheelModel().evaluate(state, w.side, model.track(), contact::RigidRailDeformation(), cd.work[i], out, cd.cost);
  ++cd.evaluations;
  // Keep the hint on the rail section of the last valid contact point (the wheel moves < 1 mm per step).
  const contact::ContactPointResult& tread = out.contact[contact::kTread];
  if (tread.status != contact::DetectionStatus::kOutOfBounds &&
      tread.status != contact::DetectionStatus::kInvalidInput && std::isfinite(tread.s_r)) {
    cd.s_hint[i] = tread.s_r;
  }
  // Eq. 13 wrench about the taping-line point (moment in the wheelset frame) -> about the load point, world.
  const Vector3& f = out.wheel_centre.force_in_world;
  const Vector3 arm_load = b.A * w.s_load_point_in_body;
  cd.force_in_world[i] = f;
  cd.moment_in_world[i] = b.A * out.wheel_centre.moment_in_wheelset + (arm_taping - arm_load).cross(f);
}

WheelRailContactElement::WheelRailContactElement(const WheelRailContactModel* model, WheelRailContactData* contact_data)
    : ForceElement("wheel_rail_contact", model->wheels().front().body, kGround),
      model_(model),
      contact_data_(contact_data) {}

void WheelRailContactElement::addForces(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> g) const {
  WheelRailContactData& cd = *contact_data_;
  if (!cd.enabled) return;
  for (int k = 0; k < model_->nWheels(); ++k) {
    evaluateWheel(*model_, data, k, cd);
    const WheelDefinition& w = model_->wheels()[static_cast<std::size_t>(k)];
    const BodyKinematics& b = data.bodies[static_cast<std::size_t>(w.body)];
    const Vector3 p_load = b.r + b.A * w.s_load_point_in_body;
    applyForceAt(data, w.body, cd.force_in_world[static_cast<std::size_t>(k)], p_load, g);
    applyMoment(data, w.body, cd.moment_in_world[static_cast<std::size_t>(k)], g);
  }
}

double WheelRailContactElement::potentialEnergy(const VehicleData& /*data*/) const { return 0.0; }

void WheelRailContactElement::couplingGroups(std::vector<std::vector<int>>& groups) const {
  for (const WheelDefinition& w : model_->wheels()) groups.push_back({w.body});
}

// Same-size vector assignments: element copies, no allocation.
void WheelRailContactElement::saveWorkState() const {
  contact_data_->forEachSaved([](auto& live, auto& saved) { saved = live; });
}

void WheelRailContactElement::restoreWorkState() const {
  contact_data_->forEachSaved([](auto& live, auto& saved) { live = saved; });
}

void WheelRailContactElement::acceptStep() const {
  for (contact::WheelContactWork& w : contact_data_->work) {
    w.commitAcceptedStep();
  }
}

}  // namespace rail::vehicle
