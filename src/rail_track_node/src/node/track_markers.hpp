// rviz markers of the FE track (effects.rviz_markers): the rails as line strips coloured by their vertical
// deflection (displacements magnified by `scale`) and the sleepers as a line list between their end nodes.
// The message storage is allocated once; update() only writes.
#pragma once

#include <ros/time.h>
#include <visualization_msgs/MarkerArray.h>

#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

#include "rail_track_node/track_model.hpp"

namespace rail::track {

class TrackMarkers {
 public:
  TrackMarkers(const TrackModel& model, const std::string& frame_id, double scale, double colour_range)
      : model_(model), scale_(scale), colour_range_(colour_range) {
    const TrackMesh& mesh = model.mesh;
    const double incl = model.data.layout.rail_inclination;
    msg_.markers.resize(3);
    for (int r = 0; r < 2; ++r) {
      visualization_msgs::Marker& m = msg_.markers[r];
      m.header.frame_id = frame_id;
      m.ns = "rails";
      m.id = r;
      m.type = visualization_msgs::Marker::LINE_STRIP;
      m.action = visualization_msgs::Marker::ADD;
      m.pose.orientation.w = 1.0;
      m.scale.x = 0.07;  // line width, m (rail head width)
      m.color.a = 1.0;
      const std::size_t n = mesh.rail_nodes[r].size();
      m.points.resize(n);
      m.colors.resize(n);
      up_[r].resize(n);
      const double sg = r == kLeftRail ? 1.0 : -1.0;
      for (std::size_t k = 0; k < n; ++k) {
        const int beam = mesh.rail_beams[r][k + 1 < n ? k : k - 1];
        const Eigen::Matrix3d& R = mesh.beams[beam].R_local_to_world;
        up_[r][k] = sg * std::sin(incl) * R.col(1) + std::cos(incl) * R.col(2);  // track normal
      }
    }
    visualization_msgs::Marker& s = msg_.markers[2];
    s.header.frame_id = frame_id;
    s.ns = "sleepers";
    s.id = 0;
    s.type = visualization_msgs::Marker::LINE_LIST;
    s.action = visualization_msgs::Marker::ADD;
    s.pose.orientation.w = 1.0;
    s.scale.x = 0.22;  // line width, m (sleeper width)
    s.color.r = s.color.g = s.color.b = 0.55f;
    s.color.a = 1.0;
    s.points.resize(2 * mesh.sleeper_nodes.size());
  }

  const visualization_msgs::MarkerArray& update(const Eigen::VectorXd& d, const ros::Time& stamp) {
    const TrackMesh& mesh = model_.mesh;
    for (int r = 0; r < 2; ++r) {
      visualization_msgs::Marker& m = msg_.markers[r];
      m.header.stamp = stamp;
      for (std::size_t k = 0; k < m.points.size(); ++k) {
        const int node = mesh.rail_nodes[r][k];
        const Eigen::Vector3d u = translation(d, node);
        const Eigen::Vector3d p = mesh.nodes[node].p_in_world + scale_ * u;
        m.points[k].x = p.x();
        m.points[k].y = p.y();
        m.points[k].z = p.z();
        // 0 (no deflection, blue) .. 1 (colour_range down, red).
        const double w = std::min(1.0, std::max(0.0, -u.dot(up_[r][k]) / colour_range_));
        m.colors[k].r = static_cast<float>(w);
        m.colors[k].g = static_cast<float>(0.3 * (1.0 - w));
        m.colors[k].b = static_cast<float>(1.0 - w);
        m.colors[k].a = 1.0f;
      }
    }
    visualization_msgs::Marker& s = msg_.markers[2];
    s.header.stamp = stamp;
    for (std::size_t k = 0; k < mesh.sleeper_nodes.size(); ++k) {
      for (int e = 0; e < 2; ++e) {
        const int node = mesh.sleeper_nodes[k][e == 0 ? 0 : 5];
        const Eigen::Vector3d p = mesh.nodes[node].p_in_world + scale_ * translation(d, node);
        s.points[2 * k + e].x = p.x();
        s.points[2 * k + e].y = p.y();
        s.points[2 * k + e].z = p.z();
      }
    }
    return msg_;
  }

 private:
  Eigen::Vector3d translation(const Eigen::VectorXd& d, int node) const {
    Eigen::Vector3d u;
    for (int q = 0; q < 3; ++q) {
      const int i = model_.mesh.dofIndex(node, q);
      u(q) = i >= 0 ? d(i) : 0.0;
    }
    return u;
  }
  const TrackModel& model_;
  double scale_, colour_range_;
  std::array<std::vector<Eigen::Vector3d>, 2> up_;
  visualization_msgs::MarkerArray msg_;
};

}  // namespace rail::track
