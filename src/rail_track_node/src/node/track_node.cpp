// rail_track node: the track side of a railsim run. Reads and validates the scene, then runs the
// co-simulation's track side, a replay of recorded wheel states or the moving loads (runTrackSide,
// track_side.hpp). Physics and run rules live in the ROS-free core (cosim_track.hpp, cosim_track_run.hpp,
// track_simulator.hpp).
#include <rail_ros/node_scaffold.hpp>

#include "track_side.hpp"

int main(int argc, char** argv) {
  return rail::ros_glue::nodeMain(argc, argv, "rail_track",
                                  "the track side of a railsim run (FE track and the wheel-rail contact in "
                                  "co-simulation, moving loads, replay)",
                                  rail::core::Role::kTrack, rail::track::runTrackSide);
}
