#include "rail_vehicle_node/vehicle_loader.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <rail_contact/format.hpp>

#include "rail_core/yaml_reader.hpp"

namespace rail::vehicle {

using contact::formatNumber;

namespace {

using core::describe;
using core::MapReader;

[[noreturn]] void raiseVehicleFileError(const std::string& message) { throw VehicleFileError(message); }

// Magnitude bounds of the vehicle data, refused above (never clamped). Far beyond any rail vehicle, they
// only catch mistyped or corrupted values that would make the integration fail.
constexpr double kMaxPosition = 1e3;    // m, |coordinate| of a position, offset, length or deflection
constexpr double kMaxForce = 1e8;       // N, |preload| or bump-stop force (a loaded axle: 2e5 N)
constexpr double kMaxStiffness = 1e12;  // N/m or N m/rad
constexpr double kMaxDamping = 1e12;    // N s/m or N m s/rad
constexpr double kMaxMass = 1e6;        // kg (a loaded coach: 6e4 kg)
constexpr double kMaxInertia = 1e8;     // kg m^2, |principal moment| or |product| (a carbody: 3e6)
// kg m^2, principal moment: 1 g at 1 mm from the axis. Below it the body's angular accelerations dwarf every
// other rate of the model (an axlebox: 10 kg m^2) and no integrator step resolves them.
constexpr double kMinInertia = 1e-6;
constexpr double kMaxGravity = 1e3;        // m/s^2, |component| of the gravity vector
constexpr double kMaxAxisComponent = 1e6;  // dimensionless, |component| of a direction before normalising

// Body index of the name at key; "ground" is the fixed frame where allowed.
int bodyOf(MapReader& r, const VehicleModel& model, const char* key, bool ground_allowed) {
  const std::string name = r.name(key);
  for (int b = 0; b < model.nBodies(); ++b) {
    if (model.bodies()[static_cast<std::size_t>(b)].name == name) return b;
  }
  if (name == "ground") {
    if (ground_allowed) return kGround;
    r.fail(key, "the ground cannot be used here, got 'ground'");
  }
  r.fail(key, "no body of that name is defined, got '" + name + "'");
}

// A list of 3 numbers in [0, max]; zero when absent.
Vector3 nonNegativeVector3(MapReader& r, const char* key, double max, const char* unit) {
  const Vector3 v = r.optionalVector3(key, max, unit);
  for (int k = 0; k < 3; ++k) {
    if (v[k] < 0.0) {
      const YAML::Node item = r.node(key)[static_cast<std::size_t>(k)];
      r.failAtNode(item, r.field(key) + "[" + std::to_string(k) + "]",
                   "must not be negative, got " + formatNumber(v[k]));
    }
  }
  return v;
}

// A direction: 3 numbers, not all zero.
Vector3 axisOf(MapReader& r, const char* key) {
  const Vector3 axis = r.vector3(key, kMaxAxisComponent, "");
  if (axis.norm() < 1e-12) r.fail(key, "axis must not be zero, got " + describe(r.node(key)));
  return axis;
}

// Runs a model builder call, turning its std::runtime_error into a file error at the element's path.
template <typename F>
void build(const MapReader& r, F&& call) {
  try {
    call();
  } catch (const VehicleFileError&) {
    throw;
  } catch (const std::runtime_error& e) {
    r.failHere(std::string(e.what()) + ", got " + describe(r.node("name")));
  }
}

// Each element of the list at key, as a map reader with its path "key[i]".
template <typename F>
void forEachElement(MapReader& root, const char* key, bool required, F&& read) {
  const YAML::Node items = root.list(key, required);
  for (std::size_t k = 0; k < items.size(); ++k) {
    MapReader r(items[k], std::string(key) + "[" + std::to_string(k) + "]", root.file(), root.raise());
    read(r);
  }
}

// A name that must be new within its kind.
std::string newName(MapReader& r, std::set<std::string>& names, const char* kind) {
  const std::string name = r.name("name");
  if (!names.insert(name).second) r.fail("name", std::string(kind) + " defined twice, got '" + name + "'");
  return name;
}

void readBody(MapReader& r, VehicleModel& model) {
  RigidBody body;
  body.name = r.name("name");
  for (const auto& b : model.bodies()) {
    if (b.name == body.name) r.fail("name", "body defined twice, got '" + body.name + "'");
  }
  if (body.name == "ground") r.fail("name", "reserved name, got 'ground'");
  body.mass = r.positive("mass", kMaxMass, "kg");
  body.r_reference = r.vector3("centre_of_mass", kMaxPosition, "m");
  const Vector3 principal = r.vector3("inertia", kMaxInertia, "kg m^2");
  for (int i = 0; i < 3; ++i) {
    const YAML::Node item = r.node("inertia")[static_cast<std::size_t>(i)];
    const std::string path = r.field("inertia") + "[" + std::to_string(i) + "]";
    if (!(principal[i] > 0.0)) r.failAtNode(item, path, "must be positive, got " + formatNumber(principal[i]));
    if (!(principal[i] >= kMinInertia)) {
      r.failAtNode(item, path,
                   "must be at least " + formatNumber(kMinInertia) + " kg m^2, got " + formatNumber(principal[i]));
    }
  }
  const Vector3 products = r.optionalVector3("products_of_inertia", kMaxInertia, "kg m^2");
  body.inertia_in_body << principal[0], products[0], products[1], products[0], principal[1], products[2], products[1],
      products[2], principal[2];
  r.finish();
  build(r, [&] { model.addBody(body); });
}

// What a joint and a force element begin with: a type among three, a new name and two different bodies.
struct Connection {
  std::string type, name;
  int body_i = 0, body_j = 0;
};
Connection readConnection(MapReader& r, const VehicleModel& model, std::set<std::string>& names, const char* type_kind,
                          const char* kind, const std::array<const char*, 3>& types, bool ground_as_body_i) {
  Connection c;
  c.type = r.name("type");
  if (std::find(types.begin(), types.end(), c.type) == types.end())
    r.fail("type", std::string("unknown ") + type_kind + " type (expected " + types[0] + ", " + types[1] + " or " +
                       types[2] + "), got '" + c.type + "'");
  c.name = newName(r, names, kind);
  c.body_i = bodyOf(r, model, "body_i", ground_as_body_i);
  c.body_j = bodyOf(r, model, "body_j", true);
  if (c.body_i == c.body_j)
    r.fail("body_j", std::string("a ") + kind + " needs two different bodies, got " + describe(r.node("body_j")));
  return c;
}

void readJoint(MapReader& r, VehicleModel& model, std::set<std::string>& names) {
  const Connection c = readConnection(r, model, names, "joint", "joint", {"revolute", "spherical", "fixed"}, false);
  const Vector3 p = r.vector3("position", kMaxPosition, "m");
  const Vector3 axis = c.type == "revolute" ? axisOf(r, "axis") : Vector3::Zero();
  r.finish();
  build(r, [&] {
    if (c.type == "revolute") {
      model.addRevoluteJointAt(c.name, c.body_i, c.body_j, p, axis.normalized());
    } else if (c.type == "spherical") {
      model.addSphericalJointAt(c.name, c.body_i, c.body_j, p);
    } else {
      model.addFixedJointAt(c.name, c.body_i, c.body_j, p);
    }
  });
}

// A bump stop's characteristic: rows [deflection, force], the first [clearance >= 0, 0], deflection
// increasing, force not decreasing.
void readBumpStopTable(MapReader& r, std::vector<double>& deflections, std::vector<double>& magnitudes) {
  const YAML::Node table = r.list("table", true);
  if (table.size() < 2) r.fail("table", "must be a list of >= 2 [deflection, force] rows, got " + describe(table));
  for (std::size_t k = 0; k < table.size(); ++k) {
    const std::string row_path = r.field("table") + "[" + std::to_string(k) + "]";
    const YAML::Node row = table[k];
    if (!row.IsSequence() || row.size() != 2)
      r.failAtNode(row, row_path, "must be [deflection, force], got " + describe(row));
    const double d = r.boundedAt(row[0], row_path + "[0]", kMaxPosition, "m");
    const double f = r.boundedAt(row[1], row_path + "[1]", kMaxForce, "N");
    if (k == 0 && (d < 0.0 || f != 0.0))
      r.failAtNode(row, row_path, "first row must be [clearance >= 0, 0], got " + describe(row));
    if (k > 0 && !(d > deflections.back())) {
      r.failAtNode(
          row[0], row_path + "[0]",
          "deflection not increasing (after " + formatNumber(deflections.back()) + "), got " + formatNumber(d));
    }
    if (k > 0 && f < magnitudes.back()) {
      r.failAtNode(row[1], row_path + "[1]",
                   "force decreasing (after " + formatNumber(magnitudes.back()) + "), got " + formatNumber(f));
    }
    deflections.push_back(d);
    magnitudes.push_back(f);
  }
}

void readForce(MapReader& r, VehicleModel& model, std::set<std::string>& names) {
  const Connection c =
      readConnection(r, model, names, "force", "force element", {"bushing", "point_to_point", "bump_stop"}, true);
  if (c.type == "bushing") {
    Bushing::Parameters par;
    par.stiffness = nonNegativeVector3(r, "stiffness", kMaxStiffness, "N/m");
    par.damping = nonNegativeVector3(r, "damping", kMaxDamping, "N s/m");
    par.preload = r.optionalVector3("preload", kMaxForce, "N");
    par.free_offset = r.optionalVector3("free_offset", kMaxPosition, "m");
    par.rotational_stiffness = nonNegativeVector3(r, "rotational_stiffness", kMaxStiffness, "N m/rad");
    par.rotational_damping = nonNegativeVector3(r, "rotational_damping", kMaxDamping, "N m s/rad");
    const Vector3 p = r.vector3("position", kMaxPosition, "m");
    r.finish();
    build(r, [&] { model.addBushingAt(c.name, c.body_i, c.body_j, p, Matrix3::Identity(), par); });
  } else if (c.type == "point_to_point") {
    const Vector3 p_i = r.vector3("position_i", kMaxPosition, "m");
    const Vector3 p_j = r.vector3("position_j", kMaxPosition, "m");
    const double stiffness = r.optionalBounded("stiffness", 0.0, kMaxStiffness, "N/m");
    const double damping = r.optionalBounded("damping", 0.0, kMaxDamping, "N s/m");
    const double free_length = r.optionalBounded("free_length", -1.0, kMaxPosition, "m");
    const double preload = r.optionalBounded("preload", 0.0, kMaxForce, "N");
    if (stiffness < 0.0) r.fail("stiffness", "must not be negative, got " + formatNumber(stiffness));
    if (damping < 0.0) r.fail("damping", "must not be negative, got " + formatNumber(damping));
    if (r.has("free_length") && free_length < 0.0)
      r.fail("free_length", "must not be negative, got " + formatNumber(free_length));
    if ((p_j - p_i).norm() < 1e-9)
      r.fail("position_j", "must differ from position_i, got " + describe(r.node("position_j")));
    r.finish();
    build(r, [&] {
      model.addPointToPointAt(c.name, c.body_i, c.body_j, p_i, p_j, stiffness, damping, free_length, preload);
    });
  } else {
    const Vector3 p = r.vector3("position", kMaxPosition, "m");
    const Vector3 axis = axisOf(r, "axis");
    std::vector<double> deflections, magnitudes;
    readBumpStopTable(r, deflections, magnitudes);
    r.finish();
    build(r, [&] { model.addBumpStopAt(c.name, c.body_i, c.body_j, p, axis.normalized(), deflections, magnitudes); });
  }
}

}  // namespace

void loadVehicleInto(const std::string& path, VehicleModel& model) {
  const YAML::Node root_node = core::loadYamlFile(path, raiseVehicleFileError);
  MapReader root(root_node, "", path, raiseVehicleFileError);
  // Descriptive keys, not used by the model.
  root.child("name");
  root.child("description");
  root.child("parameters");

  if (root.has("gravity")) {
    const Vector3 g = root.vector3("gravity", kMaxGravity, "m/s^2");
    try {
      model.setGravity(g);
    } catch (const std::runtime_error& e) {
      root.fail("gravity", std::string(e.what()) + ", got " + describe(root.node("gravity")));
    }
  } else {
    root.child("gravity");
  }

  forEachElement(root, "bodies", true, [&](MapReader& r) { readBody(r, model); });
  // Load points and measurement points (reported motion only, e.g. floor accelerometers): a name, a body
  // and a position each.
  using AddPoint = int (VehicleModel::*)(const std::string&, int, const Vector3&);
  for (const auto& [key, add] : {std::pair<const char*, AddPoint>{"load_points", &VehicleModel::addLoadPointAtWorld},
                                 {"measurement_points", &VehicleModel::addMeasurementPointAtWorld}}) {
    forEachElement(root, key, false, [&, add = add](MapReader& r) {
      const std::string name = r.name("name");
      const int body = bodyOf(r, model, "body", false);
      const Vector3 p = r.vector3("position", kMaxPosition, "m");
      r.finish();
      build(r, [&] { (model.*add)(name, body, p); });
    });
  }
  std::set<std::string> joint_names;
  forEachElement(root, "joints", false, [&](MapReader& r) { readJoint(r, model, joint_names); });
  std::set<std::string> force_names;
  forEachElement(root, "forces", false, [&](MapReader& r) { readForce(r, model, force_names); });
  root.finish();
}

VehicleModel loadVehicleModel(const std::string& path) {
  VehicleModel model;
  loadVehicleInto(path, model);
  model.finalize();
  return model;
}

}  // namespace rail::vehicle
