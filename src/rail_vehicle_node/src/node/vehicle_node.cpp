// rail_vehicle node: the vehicle side of a railsim run. Reads and validates the scene, then runs the
// vehicle alone on the rigid track or co-simulated with rail_track (runVehicleSide, vehicle_side.hpp).
// Physics and run rules live in the core.
#include <rail_ros/node_scaffold.hpp>

#include "vehicle_side.hpp"

int main(int argc, char** argv) {
  return rail::ros_glue::nodeMain(argc, argv, "rail_vehicle",
                                  "the vehicle side of a railsim run (multibody vehicle on CVODE; alone on the "
                                  "rigid track or co-simulated with rail_track)",
                                  rail::core::Role::kVehicle, rail::vehicle::runVehicleSide);
}
