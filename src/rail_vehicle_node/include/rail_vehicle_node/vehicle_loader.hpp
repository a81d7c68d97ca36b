// Loads a vehicle data file (YAML; e.g. config/vehicle/paper_coach.yaml) into a VehicleModel.
//
// File layout (SI units, world frame x forward, y left, z up, all positions at the reference
// configuration; body axes are parallel to the world axes there):
//   name, description: text                                 optional, not used
//   gravity: [gx, gy, gz]                                   optional, default [0, 0, -9.81]
//   parameters: {...}                                       free-form, for YAML anchors; not read
//   bodies:      - {name, mass, centre_of_mass: [x,y,z], inertia: [Jxx, Jyy, Jzz],
//                   products_of_inertia: [Jxy, Jxz, Jyz] (optional)}
//   load_points: - {name, body, position}                   e.g. wheel centres
//   measurement_points: - {name, body, position}            reported motion only (floor accelerometers)
//   joints:      - {name, type: revolute|spherical|fixed, body_i, body_j (or "ground"), position,
//                   axis (revolute)}
//   forces:      - {name, type: bushing, body_i, body_j, position, stiffness, damping,
//                   preload, free_offset, rotational_stiffness, rotational_damping (3-vectors, optional)}
//                - {name, type: point_to_point, body_i, body_j, position_i, position_j, stiffness,
//                   damping, free_length (optional: reference distance), preload (optional)}
//                - {name, type: bump_stop, body_i, body_j, position, axis, table: [[deflection, force], ...]}
// Errors throw VehicleFileError "<file>: <key.path>: <what>, got <value> (line N)".
#pragma once

#include <stdexcept>
#include <string>

#include "rail_vehicle_node/vehicle_model.hpp"

namespace rail::vehicle {

class VehicleFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Adds the file's bodies, load points, joints and force elements to a model that is still being built
// (so the caller may add more before Finalize()).
void loadVehicleInto(const std::string& path, VehicleModel& model);

// Loads the file into a new, finalised model.
VehicleModel loadVehicleModel(const std::string& path);

}  // namespace rail::vehicle
