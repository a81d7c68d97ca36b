#include "cosim_outputs.hpp"

#include <algorithm>
#include <utility>

#include <rail_core/exit_codes.hpp>
#include <rail_ros/contact_point_message.hpp>

#include "track_messages.hpp"

namespace rail::track {

using core::CostProfile;

CosimTrackOutputs::CosimTrackOutputs(ros::NodeHandle& nh, ros::NodeHandle& pnh, core::OutputSettings settings,
                                     const CosimTrack& track, core::CostProfile& cost, core::CostClock& clock)
    : settings_(std::move(settings)), track_(track), cost_(cost), clock_(clock) {
  deflections_ = settings_.effects.rail_deflection_output && !settings_.output.deflection_sections.empty();
  // Pad forces under the train: the sleepers from output.pad_force_margin behind the rearmost wheel to as
  // far ahead of the foremost one.
  pads_ = settings_.effects.pad_force_output && track.flexible();
  energy_ = settings_.effects.energy_output && track.flexible();
  // The rigid FE track has no mesh to draw.
  markers_on_ = settings_.effects.rviz_markers && track.flexible();
  rec_points_ = settings_.effects.contact_point_output && settings_.records("contact_points");
  rec_deflection_ = deflections_ && settings_.records("rail_deflection");
  rec_pads_ = pads_ && settings_.records("pad_forces");
  rec_energy_ = energy_ && settings_.records("track_energy");

  if (settings_.effects.contact_point_output)
    points_pub_ = nh.advertise<rail_msgs::ContactPoints>("/contact_points", 100);
  if (deflections_) deflection_pub_ = nh.advertise<rail_msgs::RailDeflection>("/rail_deflection", 100);
  if (pads_) pads_pub_ = nh.advertise<rail_msgs::RailPadForces>("/pad_forces", 100);
  if (energy_) energy_pub_ = nh.advertise<rail_msgs::Energy>("/track_energy", 100);

  points_msg_.header.frame_id = "world";
  points_msg_.points.resize(rail::contact::kContactSlots * static_cast<std::size_t>(track.wheelCount()));
  deflection_msgs_.resize(static_cast<std::size_t>(track.sectionCount()));
  for (rail_msgs::RailDeflection& m : deflection_msgs_) m.header.frame_id = "track";
  pad_samples_.resize(pads_ ? static_cast<std::size_t>(track.sleeperCount()) : 0u);
  pads_msg_.header.frame_id = "track";
  for (auto* v : {&pads_msg_.left_pad_force, &pads_msg_.right_pad_force, &pads_msg_.left_rail_displacement,
                  &pads_msg_.right_rail_displacement, &pads_msg_.ballast_force}) {
    v->reserve(pad_samples_.size());
  }
  pads_msg_.arc_length.reserve(pad_samples_.size());
  pads_msg_.ballast_gap.reserve(pad_samples_.size());
  energy_msg_.header.frame_id = "track";

  marker_params_ = rail::ros_glue::markerParams(pnh);
  if (markers_on_) {
    marker_pub_ = nh.advertise<visualization_msgs::MarkerArray>("/markers", 2, true);
    if (track.trackWindow() == nullptr) markers_ = makeMarkers(track.sceneTrack()->model);
    marker_period_ = marker_params_.period(settings_.output.rate);
  }
}

std::unique_ptr<TrackMarkers> CosimTrackOutputs::makeMarkers(const TrackModel& model) const {
  const rail::ros_glue::MarkerParams& m = marker_params_;
  return std::make_unique<TrackMarkers>(model, m.frame_id, m.scale, m.colour_range);
}

bool CosimTrackOutputs::openBag(const std::string& node, ros::NodeHandle& pnh) {
  if (settings_.output.bag.empty() || !(rec_points_ || rec_deflection_ || rec_pads_ || rec_energy_)) return true;
  const std::string path = rail::ros_glue::besideBag(rail::ros_glue::bagPath(pnh, settings_.output.bag), ".track.bag");
  if (!bag_.open(node, settings_.source, path)) return false;
  ROS_INFO("%s: recording the track's outputs to %s", node.c_str(), path.c_str());
  return true;
}

void CosimTrackOutputs::publish(const ros::Time& stamp, const core::coupling::WheelStateFrame& states) {
  CostProfile::Scope timing(cost_, CostProfile::kPublish);
  core::timedOutput(&clock_, core::CostClock::kContactPointOutput, settings_.effects.contact_point_output, [&] {
    points_msg_.header.stamp = stamp;
    for (int id = 0; id < track_.wheelCount(); ++id) {
      for (int k = 0; k < rail::contact::kContactSlots; ++k) {
        rail_msgs::ContactPoint& p =
            points_msg_
                .points[rail::contact::kContactSlots * static_cast<std::size_t>(id) + static_cast<std::size_t>(k)];
        rail::ros_glue::toMessage(track_.contact(id).contact[k], id, id % 2, p);
      }
    }
    points_pub_.publish(points_msg_);
    if (rec_points_ && bag_.isOpen()) {
      CostProfile::Scope bag_timing(cost_, CostProfile::kBagWrite);
      bag_.write("/contact_points", stamp, points_msg_);
    }
  });
  for (int i = 0; i < track_.sectionCount(); ++i) {
    track_.sectionDeflection(i, deflection_);
    rail_msgs::RailDeflection& m = deflection_msgs_[static_cast<std::size_t>(i)];
    fill(m, deflection_, stamp);
    deflection_pub_.publish(m);
    if (rec_deflection_ && bag_.isOpen()) {
      CostProfile::Scope bag_timing(cost_, CostProfile::kBagWrite);
      bag_.write("/rail_deflection", stamp, m);
    }
  }
  if (pads_) {
    double s_min = 1e300, s_max = -1e300;
    for (std::uint32_t i = 0; i < states.count; ++i) {
      s_min = std::min(s_min, states.wheels[i].arc_length);
      s_max = std::max(s_max, states.wheels[i].arc_length);
    }
    const int n = track_.padForces(s_min - settings_.output.pad_force_margin, s_max + settings_.output.pad_force_margin,
                                   pad_samples_.data(), static_cast<int>(pad_samples_.size()));
    pads_msg_.header.stamp = stamp;
    const auto size = static_cast<std::size_t>(n);  // within the reserved capacity: no allocation
    pads_msg_.arc_length.resize(size);
    pads_msg_.left_pad_force.resize(size);
    pads_msg_.right_pad_force.resize(size);
    pads_msg_.left_rail_displacement.resize(size);
    pads_msg_.right_rail_displacement.resize(size);
    pads_msg_.ballast_force.resize(size);
    pads_msg_.ballast_gap.resize(size);
    for (std::size_t k = 0; k < size; ++k) {
      const PadForceSample& p = pad_samples_[k];
      pads_msg_.arc_length[k] = p.arc_length;
      fill(pads_msg_.left_pad_force[k], p.force_in_track[kLeftRail]);
      fill(pads_msg_.right_pad_force[k], p.force_in_track[kRightRail]);
      fill(pads_msg_.left_rail_displacement[k], p.rail_displacement_in_track[kLeftRail]);
      fill(pads_msg_.right_rail_displacement[k], p.rail_displacement_in_track[kRightRail]);
      fill(pads_msg_.ballast_force[k], p.ballast_force_in_track);
      pads_msg_.ballast_gap[k] = p.ballast_gap;
    }
    pads_pub_.publish(pads_msg_);
    if (rec_pads_ && bag_.isOpen()) {
      CostProfile::Scope bag_timing(cost_, CostProfile::kBagWrite);
      bag_.write("/pad_forces", stamp, pads_msg_);
    }
  }
  core::timedOutput(&clock_, core::CostClock::kEnergyOutput, energy_, [&] {
    track_.energy(energy_msg_.kinetic, energy_msg_.potential);
    energy_msg_.total = energy_msg_.kinetic + energy_msg_.potential;
    energy_msg_.header.stamp = stamp;
    energy_pub_.publish(energy_msg_);
    if (rec_energy_ && bag_.isOpen()) {
      CostProfile::Scope bag_timing(cost_, CostProfile::kBagWrite);
      bag_.write("/track_energy", stamp, energy_msg_);
    }
  });
  core::timedOutput(&clock_, core::CostClock::kMarkers, markers_on_ && stamp.toSec() + 1e-12 >= next_marker_,
                    [&] { publishMarkers(stamp); });
}

void CosimTrackOutputs::publishMarkers(const ros::Time& stamp) {
  next_marker_ += marker_period_;
  const TrackWindow* window = track_.trackWindow();
  if (window == nullptr) {
    marker_pub_.publish(markers_->update(track_.state()->d, stamp));
    return;
  }
  if (track_.windowMoves() != marker_window_moves_) {  // a new mesh: rebuild (allocates; rare)
    marker_window_moves_ = track_.windowMoves();
    markers_ = makeMarkers(window->model());
    d_total_.resize(window->staticState().size());
  }
  d_total_ = window->staticState() + window->state().d;
  marker_pub_.publish(markers_->update(d_total_, stamp));
}

void CosimTrackOutputs::close(const std::string& node, const CosimTrackRun& run, int exit_code, double wall) {
  cost_.add(CostProfile::kPublish, -cost_.seconds(CostProfile::kBagWrite));  // bag writes are inside publishing
  cost_.setCount("track_steps", static_cast<double>(run.steps()));
  cost_.setCount("newmark_steps", static_cast<double>(track_.newmarkSteps()));
  if (track_.trackWindow() != nullptr) {
    cost_.setCount("window_moves", track_.windowMoves());
    cost_.setCount("window_rebuilds", track_.windowRebuilds());
    cost_.setCount("window_move_ms_total", 1e3 * track_.windowMoveSeconds());
  }
  ROS_INFO_STREAM(cost_.toText(node, wall, run.time(), &clock_));
  bag_.close(node);
  bag_.writeBeside(
      node, ".cost.yaml",
      cost_.toYaml(node, settings_.source, settings_.effects, wall, run.time(), &clock_));  // <stem>.track.cost.yaml
  ROS_INFO("%s: %s after %llu steps (t = %.4f s), %ld Newmark steps, %.2f s wall", node.c_str(),
           exit_code == core::kExitOk ? "finished" : "stopped", static_cast<unsigned long long>(run.steps()),
           run.time(), track_.newmarkSteps(), wall);
  contact::DetectionCounts detection;
  for (int id = 0; id < track_.wheelCount(); ++id)
    for (const contact::DetectionWork& d : track_.contactWork(id).detection) detection.add(d);
  rail::ros_glue::logDetection(node, detection);
}

}  // namespace rail::track
