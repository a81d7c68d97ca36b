// Helpers shared by the ROS service and topic transports (private to rail_ros).
#pragma once

#include <algorithm>
#include <atomic>
#include <chrono>
#include <string>

#include <ros/init.h>

#include <rail_contact/format.hpp>

#include "rail_core/coupling/transport.hpp"

namespace rail::ros_glue::detail {

// Longest sleep between checks of the interrupt flag, of ros::ok() and of the peer's connection.
constexpr auto kSlice = std::chrono::milliseconds(20);

// kInterrupted when the caller's flag is raised or roscpp is shutting down; kOk otherwise.
inline coupling::Result interrupted(const std::atomic<bool>* flag) {
  if (flag && flag->load(std::memory_order_relaxed)) return {coupling::Status::kInterrupted, {}};
  if (!ros::ok()) return {coupling::Status::kInterrupted, "ROS is shutting down"};
  return {};
}

// End of the next wait slice.
inline coupling::Deadline sliceEnd(coupling::Deadline deadline) {
  return std::min(deadline, coupling::Clock::now() + std::chrono::duration_cast<coupling::Clock::duration>(kSlice));
}

inline coupling::Result wrongRole(coupling::Role role, const char* call) {
  return {coupling::Status::kError, std::string(call) + " called on the " + coupling::toString(role) + " end"};
}

// "node /x" or "<role> node (name not known yet)".
inline std::string nodeLabel(const std::string& node, coupling::Role peer) {
  if (node.empty()) return std::string("the ") + coupling::toString(peer) + " node (name not known yet)";
  return "node " + node;
}

// The node that provides `service`, from the master's system state; empty when unknown or unreachable.
std::string serviceProvider(const std::string& service);

}  // namespace rail::ros_glue::detail

// The names both transports' sources use unqualified.
namespace rail::ros_glue {
using contact::formatNumber;
using coupling::Clock;
using coupling::Deadline;
using coupling::Result;
using coupling::Role;
using coupling::Status;
using detail::interrupted;
using detail::nodeLabel;
using detail::sliceEnd;
}  // namespace rail::ros_glue
