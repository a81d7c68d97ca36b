// What the track node publishes in a co-simulation, at output.rate: /contact_points (world),
// /rail_deflection (track frame, output.deflection_sections), /pad_forces and /track_energy (flexible track)
// and the rviz markers of the deflected track; what output.topics names of them goes to the companion bag
// <stem>.track.bag beside the vehicle's (the vehicle node records the run's own bag). Messages are sized at
// set-up and refilled in place.
#pragma once

#include <ros/ros.h>

#include <memory>
#include <string>
#include <vector>

#include <rail_msgs/ContactPoints.h>
#include <rail_msgs/Energy.h>
#include <rail_msgs/RailDeflection.h>
#include <rail_msgs/RailPadForces.h>
#include <rail_core/cost_profile.hpp>
#include <rail_core/coupling/frames.hpp>
#include <rail_core/run_settings.hpp>
#include <rail_ros/run_output.hpp>

#include "rail_track_node/cosim_track.hpp"
#include "rail_track_node/cosim_track_run.hpp"
#include "track_markers.hpp"

namespace rail::track {

class CosimTrackOutputs {
 public:
  // Advertises what the settings' effects call for. track, cost and clock must outlive the outputs.
  CosimTrackOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, core::OutputSettings settings, const CosimTrack& track,
                    core::CostProfile& cost, core::CostClock& clock);

  // Opens the companion bag when output.bag is set and output.topics names a track output. False after a
  // FATAL line naming the scene's output.bag.
  bool openBag(const std::string& node, ros::NodeHandle& pnh);

  // Publishes (and records) the outputs of the step whose vehicle frame is `states`.
  void publish(const ros::Time& stamp, const core::coupling::WheelStateFrame& states);

  // The run's end: the cost profile on the console and beside the closed bag, the closing line (steps,
  // Newmark steps, wall time) and how the contact was found. wall: the run loop's wall time [s].
  void close(const std::string& node, const CosimTrackRun& run, int exit_code, double wall);

  // The bag and the files beside it: failed() once a write failed (the run then stops), error() says which.
  const rail::ros_glue::OutputBag& bag() const { return bag_; }

 private:
  void publishMarkers(const ros::Time& stamp);

  const core::OutputSettings settings_;
  const CosimTrack& track_;
  core::CostProfile& cost_;
  core::CostClock& clock_;
  rail::ros_glue::OutputBag bag_;

  bool deflections_, pads_, energy_, markers_on_;
  bool rec_points_, rec_deflection_, rec_pads_, rec_energy_;
  ros::Publisher points_pub_, deflection_pub_, pads_pub_, energy_pub_, marker_pub_;
  rail_msgs::ContactPoints points_msg_;
  std::vector<rail_msgs::RailDeflection> deflection_msgs_;
  RailSectionDeflection deflection_;
  std::vector<PadForceSample> pad_samples_;
  rail_msgs::RailPadForces pads_msg_;
  rail_msgs::Energy energy_msg_;

  // Markers: on a moving window they follow the window's mesh (rebuilt after each move) and show its total
  // displacement d_g + w.
  std::unique_ptr<TrackMarkers> markers_;
  rail::ros_glue::MarkerParams marker_params_;
  std::unique_ptr<TrackMarkers> makeMarkers(const TrackModel& model) const;
  double marker_period_ = 0.0, next_marker_ = 0.0;
  int marker_window_moves_ = -1;
  Eigen::VectorXd d_total_;
};

}  // namespace rail::track
