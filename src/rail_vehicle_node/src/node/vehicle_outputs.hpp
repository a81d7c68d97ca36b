// What the vehicle node publishes at each output instant, alone or co-simulated: /clock, wheel states,
// contact points (alone: the vehicle's own contact), contact wrenches, wheelset kinematics, floor
// accelerations and energy (when the scene's effects call for them), tf frames and rviz markers; and what
// output.topics names of them goes to output.bag. Messages are sized at set-up and refilled in place.
#pragma once

#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <rail_core/cost_profile.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/run_settings.hpp>
#include <rail_ros/run_output.hpp>
#include <rail_vehicle_node/cosim_vehicle.hpp>
#include <rail_vehicle_node/vehicle_simulator.hpp>

namespace rail::vehicle {

struct OutputMessages;
struct VehicleMarkers;

class VehicleOutputs {
 public:
  // Advertises what the settings call for; sim, cost and clock must outlive the outputs. cosim: the contact
  // points are then the track node's. defect_outlines: the local defects the markers draw
  // (core::defectOutlines on the simulator's track).
  VehicleOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, core::OutputSettings settings,
                 const std::vector<core::DefectOutline>& defect_outlines, const VehicleSimulator& sim, bool cosim,
                 core::CostProfile& cost, core::CostClock& clock);
  ~VehicleOutputs();
  VehicleOutputs(const VehicleOutputs&) = delete;
  VehicleOutputs& operator=(const VehicleOutputs&) = delete;

  // Opens output.bag when the settings name one. False after a FATAL line naming the scene's output.bag.
  bool openBag(const std::string& node, ros::NodeHandle& pnh);

  // ~wait_for_subscribers (a topic or a list of them, default none): before the first step, waits until each
  // named topic has a subscriber, at most ~subscriber_timeout s (default 30), so a viewer started beside
  // the node sees the run from its start. A timeout warns, naming the topics, and the run goes on. False
  // after a FATAL line when a name is not a topic this node publishes.
  bool waitForSubscribers(const std::string& node, ros::NodeHandle& nh, ros::NodeHandle& pnh,
                          const std::atomic<bool>& stop);

  // Publishes (and records) the state of the simulator now, as output `index`.
  void publish(std::uint64_t index);

  // The run's end: the cost profile on the console and beside the bag (<stem>.cost.yaml), the closing line
  // (time, wall, CVODE counts), how the contact was found (alone), and the bag closed. cosim: the
  // co-simulated vehicle or null; wall: the run loop's wall time [s].
  void close(const std::string& node, const CosimVehicle* cosim, double wall, int exit_code);

  // The bag and the files beside it: failed() once a write failed (the run then stops), error() says which.
  const rail::ros_glue::OutputBag& bag() const { return bag_; }

 private:
  const core::OutputSettings settings_;
  const VehicleSimulator& sim_;
  core::CostProfile& cost_;
  core::CostClock& clock_;
  std::unique_ptr<OutputMessages> out_;
  rail::ros_glue::OutputBag bag_;
  bool own_points_, own_floor_, own_energy_;
  bool rec_states_ = false, rec_points_ = false, rec_wrenches_ = false, rec_kinematics_ = false;
  bool rec_floor_ = false, rec_energy_ = false, rec_tf_ = false, rec_clock_ = false;
  ros::Publisher pub_clock_, pub_states_, pub_points_, pub_wrenches_, pub_kinematics_, pub_floor_, pub_energy_,
      pub_markers_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  std::unique_ptr<VehicleMarkers> markers_;
  double marker_period_ = 0.0, next_marker_ = 0.0;
};

}  // namespace rail::vehicle
