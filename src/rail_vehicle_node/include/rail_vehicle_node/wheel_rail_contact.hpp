// Wheel-rail contact on the rigid track, evaluated inside the vehicle's right-hand side (paper sections
// 4.1-4.2). This is the one place where the vehicle side calls rail_contact's per-wheel evaluation
// (rail_contact/wheel_contact.hpp): each wheel's tread and flange contacts give a wrench at the wheel
// centre (eq. 13) which is applied to the wheelset at its load point, like an external wrench.
//
// Model/Data split: WheelRailContactModel (profiles, options, which load point is which wheel, the track
// geometry) is constant after building; WheelRailContactData (detection warm starts, impact memories,
// the last results) is owned by the caller. The force element added to the VehicleModel holds a pointer
// to both, so the model's data must outlive it.
#pragma once

#include <rail_contact/rail_deformation.hpp>
#include <rail_contact/track_geometry.hpp>
#include <rail_contact/wheel_contact.hpp>

#include <vector>

#include "rail_vehicle_node/force_element.hpp"
#include "rail_vehicle_node/joint.hpp"
#include "rail_vehicle_node/rigid_math.hpp"
#include "rail_vehicle_node/vehicle_data.hpp"

namespace rail::vehicle {

// One wheel of the vehicle: its wheelset body, its load point (the vehicle's wheel centre, where the
// wrench is applied) and the taping-line point (the contact code's wheel centre).
struct WheelDefinition {
  int wheelset = 0;  // 0 = leading
  contact::RailSide side = contact::RailSide::kLeft;
  int load_point = 0;                              // index in VehicleModel::load_points()
  int body = 0;                                    // the wheelset body
  Vector3 s_load_point_in_body = Vector3::Zero();  // wheel centre from the wheelset's centre of mass [m]
  Vector3 s_taping_in_body = Vector3::Zero();      // axle point in the taping-line plane [m]
};

// Constant part: the per-wheel contact model (one profile pair shared by all wheels), the rigid track
// geometry and the wheel list.
class WheelRailContactModel {
 public:
  WheelRailContactModel(const contact::TrackGeometry& track, const contact::WheelProfile& wheel_profile,
                        double nominal_radius, const contact::ProfileCurve& rail_profile,
                        const Eigen::Vector2d& rail_section_centre_yz, const contact::WheelContactOptions& options,
                        std::vector<WheelDefinition> wheels);

  const contact::TrackGeometry& track() const { return *track_; }
  const contact::WheelContactModel& wheelModel() const { return wheel_model_; }
  const std::vector<WheelDefinition>& wheels() const { return wheels_; }
  int nWheels() const { return static_cast<int>(wheels_.size()); }

 private:
  const contact::TrackGeometry* track_;
  contact::WheelContactModel wheel_model_;
  std::vector<WheelDefinition> wheels_;
};

// Per-wheel work state and the results of the last evaluation (sized once).
struct WheelRailContactData {
  explicit WheelRailContactData(const WheelRailContactModel& model);
  std::vector<contact::WheelContactWork> work;      // warm starts, impact memories
  std::vector<contact::WheelContactResult> result;  // last evaluation
  std::vector<double> s_hint;                       // track arc length near each wheel [m]
  std::vector<Vector3> force_in_world;              // on the wheel, at its load point [N]
  std::vector<Vector3> moment_in_world;             // about the load point [N m]
  // Copies of the above taken by WheelRailContactElement::saveWorkState (sized once).
  std::vector<contact::WheelContactWork> saved_work;
  std::vector<contact::WheelContactResult> saved_result;
  std::vector<double> saved_s_hint;
  std::vector<Vector3> saved_force_in_world, saved_moment_in_world;
  // Calls f(member, its saved copy) for each member above: the one list that saving and restoring share.
  template <class F>
  void forEachSaved(F&& f) {
    f(work, saved_work);
    f(result, saved_result);
    f(s_hint, saved_s_hint);
    f(force_in_world, saved_force_in_world);
    f(moment_in_world, saved_moment_in_world);
  }
  // Inside the integration a surface far from its rail skips its search (rail_contact DetectionWork::
  // skip_far_searches; the force is zero either way); true makes every surface search, so that the
  // out-of-contact gaps are exact (the output evaluations). True (every surface searches) after construction.
  void setExactGaps(bool exact);
  bool enabled = true;                   // false: no contact forces (set-up only)
  long long evaluations = 0;             // wheel evaluations since construction
  contact::ContactCost* cost = nullptr;  // optional timing of the evaluations (not owned)
};

// Evaluates wheel k from data.bodies (kinematics already computed) and stores the result, the wrench at
// the load point and the updated s_hint in contact_data. No allocation, no exception.
void evaluateWheel(const WheelRailContactModel& model, const VehicleData& data, int k,
                   WheelRailContactData& contact_data) noexcept;

// The contact of all wheels as a force element of the vehicle model: addForces evaluates every wheel and
// applies its wrench at the load point (nothing when contact_data.enabled is false).
class WheelRailContactElement : public ForceElement {
 public:
  WheelRailContactElement(const WheelRailContactModel* model, WheelRailContactData* contact_data);
  void addForces(const VehicleData& data, Eigen::Ref<Eigen::VectorXd> g) const override;
  double potentialEnergy(const VehicleData& data) const override;  // not tracked: 0
  // Each wheel's wrench depends on its own wheelset's state only: one group per wheelset body.
  void couplingGroups(std::vector<std::vector<int>>& groups) const override;
  // Warm starts, impact memories, hints and the last results.
  void saveWorkState() const override;
  void restoreWorkState() const override;
  void acceptStep() const override;  // commits the held impact memories and warm starts (commitAcceptedStep)

 private:
  const WheelRailContactModel* model_;
  WheelRailContactData* contact_data_;
};

}  // namespace rail::vehicle
