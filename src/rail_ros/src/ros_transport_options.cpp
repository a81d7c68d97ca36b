#include "rail_ros/ros_transport_options.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <rail_contact/format.hpp>
#include <rail_core/scene_loader.hpp>

#include <ros/master.h>
#include <ros/this_node.h>
#include <xmlrpcpp/XmlRpcException.h>
#include <xmlrpcpp/XmlRpcValue.h>

#include "ros_transport_util.hpp"

namespace rail::ros_glue {

using contact::formatNumber;

void checkOptions(const RosTransportOptions& o, const char* what) {
  if (const std::string why = core::trackStepRule(o.track_step); !why.empty())
    throw std::runtime_error(std::string(what) + ": track_step " + why);
  if (o.wheel_capacity < 1 || o.wheel_capacity > 256)
    throw std::runtime_error(std::string(what) + ": wheel_capacity must be in 1..256 (got " +
                             std::to_string(o.wheel_capacity) + ")");
  if (!(o.attach_timeout > 0.0) || !std::isfinite(o.attach_timeout))
    throw std::runtime_error(std::string(what) + ": attach_timeout must be > 0 s (got " +
                             formatNumber(o.attach_timeout) + ")");
}

namespace detail {

std::string serviceProvider(const std::string& service) {
  try {
    XmlRpc::XmlRpcValue args, result, payload;
    args[0] = ros::this_node::getName();
    if (!ros::master::execute("getSystemState", args, result, payload, false)) return {};
    // payload = [publishers, subscribers, services], each a list of [name, [node, ...]].
    if (payload.getType() != XmlRpc::XmlRpcValue::TypeArray || payload.size() < 3) return {};
    XmlRpc::XmlRpcValue& services = payload[2];
    for (int i = 0; i < services.size(); ++i) {
      XmlRpc::XmlRpcValue& entry = services[i];
      if (entry.size() < 2 || static_cast<std::string&>(entry[0]) != service) continue;
      if (entry[1].size() > 0) return static_cast<std::string&>(entry[1][0]);
    }
  } catch (const XmlRpc::XmlRpcException&) {
    // A malformed answer from the master: the provider stays unknown (it only serves messages).
  }
  return {};
}

}  // namespace detail
}  // namespace rail::ros_glue
