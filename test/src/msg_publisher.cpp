// Publishes one of each rail_msgs message with known values, latched, for the Python reader test.
#include <ros/ros.h>

#include <rail_msgs/ContactPoints.h>
#include <rail_msgs/ContactWrenches.h>
#include <rail_msgs/RailDeflection.h>
#include <rail_msgs/WheelStates.h>

int main(int argc, char** argv) {
  ros::init(argc, argv, "msg_publisher");
  ros::NodeHandle nh;
  auto pub_states = nh.advertise<rail_msgs::WheelStates>("wheel_states", 1, true);
  auto pub_wrenches = nh.advertise<rail_msgs::ContactWrenches>("contact_wrenches", 1, true);
  auto pub_points = nh.advertise<rail_msgs::ContactPoints>("contact_points", 1, true);
  auto pub_defl = nh.advertise<rail_msgs::RailDeflection>("rail_deflection", 1, true);

  rail_msgs::WheelStates states;
  states.header.stamp = ros::Time(1.25);
  states.step = 62500;
  states.scene_hash = 0xfedcba9876543210ULL;
  for (int i = 0; i < 8; ++i) {
    rail_msgs::WheelState w;
    w.wheel_id = i;
    w.wheelset = i / 2;
    w.side = i % 2 ? rail_msgs::WheelState::SIDE_RIGHT : rail_msgs::WheelState::SIDE_LEFT;
    w.arc_length = 25.0 - 1.0 * i;
    w.position.x = 25.0 - 1.0 * i;
    w.position.y = i % 2 ? -0.8 : 0.8;
    w.position.z = 0.445;
    w.orientation.w = 1.0;
    w.linear_velocity.x = 30.5556;
    w.angular_velocity.y = 30.5556 / 0.445;
    states.wheels.push_back(w);
  }
  rail_msgs::ContactWrenches wrenches;
  wrenches.header.stamp = ros::Time(1.25);
  wrenches.step = 62500;
  wrenches.scene_hash = states.scene_hash;
  rail_msgs::ContactWrench cw;
  cw.wheel_id = 3;
  cw.force.z = 72900.0;
  cw.moment.x = -1234.5;
  wrenches.wrenches.push_back(cw);

  rail_msgs::ContactPoints points;
  points.header.stamp = ros::Time(1.25);
  rail_msgs::ContactPoint p;
  p.wheel_id = 1;
  p.side = rail_msgs::WheelState::SIDE_RIGHT;
  p.kind = rail_msgs::ContactPoint::KIND_FLANGE;
  p.active = true;
  p.normal_force = 45000.0;
  p.semi_axis_a = 0.006;
  p.semi_axis_b = 0.004;
  p.creepage_spin = 0.35;
  points.points.push_back(p);

  rail_msgs::RailDeflection d;
  d.header.stamp = ros::Time(1.25);
  d.arc_length = 66.0;
  d.left_displacement.z = -1.1e-3;
  d.right_rotation.x = 2e-4;

  pub_states.publish(states);
  pub_wrenches.publish(wrenches);
  pub_points.publish(points);
  pub_defl.publish(d);
  ros::spin();
  return 0;
}
