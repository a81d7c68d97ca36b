#include "rail_vehicle_node/vehicle_loader.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include <rail_contact/format.hpp>

#include "rail_core/yaml_duplicates.hpp"

namespace rail::vehicle {

using contact::formatNumber;
namespace {

std::string describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

std::string join(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

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

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  // "<file>: <path>: <what>, got <value> (line N)"
  [[noreturn]] void fail(const YAML::Node& where, const std::string& path, const std::string& what,
                         const std::string& got) const {
    std::ostringstream os;
    os << file_ << ": " << path << ": " << what << ", got " << got;
    if (where.IsDefined() && where.Mark().line >= 0) os << " (line " << where.Mark().line + 1 << ")";
    throw VehicleFileError(os.str());
  }

  YAML::Node require(const YAML::Node& map, const std::string& path, const char* key) const {
    const YAML::Node node = map[key];
    if (!node.IsDefined() || node.IsNull()) fail(map, join(path, key), "required key missing", "nothing");
    return node;
  }

  void checkKeys(const YAML::Node& map, const std::string& path, std::initializer_list<const char*> allowed) const {
    if (!map.IsMap()) fail(map, path, "expected a map", describe(map));
    const std::set<std::string> keys(allowed.begin(), allowed.end());
    for (const auto& item : map) {
      const std::string key = item.first.as<std::string>();
      if (keys.count(key) == 0) {
        std::string list;
        for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
        fail(item.first, join(path, key), "unknown key (expected one of " + list + ")", key);
      }
    }
  }

  double number(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) fail(node, path, "expected a number", describe(node));
    double value = 0.0;
    try {
      value = node.as<double>();
    } catch (const YAML::Exception&) {
      fail(node, path, "expected a number", describe(node));
    }
    if (!std::isfinite(value)) fail(node, path, "expected a finite number", describe(node));
    return value;
  }

  // A finite number with |value| <= max_abs (unit names the unit of max_abs in the message).
  double bounded(const YAML::Node& node, const std::string& path, double max_abs, const char* unit) const {
    const double value = number(node, path);
    if (!(std::abs(value) <= max_abs)) {
      const std::string unit_text = *unit ? std::string(" ") + unit : std::string();
      fail(node, path, "magnitude must be <= " + formatNumber(max_abs) + unit_text, describe(node));
    }
    return value;
  }

  double optionalBounded(const YAML::Node& map, const std::string& path, const char* key, double fallback,
                         double max_abs, const char* unit) const {
    const YAML::Node node = map[key];
    if (!node.IsDefined() || node.IsNull()) return fallback;
    return bounded(node, join(path, key), max_abs, unit);
  }

  double number(const YAML::Node& map, const std::string& path, const char* key) const {
    return number(require(map, path, key), join(path, key));
  }

  // A list of 3 numbers, each with |component| <= max_abs (unit: the unit of max_abs).
  Vector3 vec3(const YAML::Node& node, const std::string& path, double max_abs, const char* unit) const {
    if (!node.IsSequence() || node.size() != 3) fail(node, path, "expected a list of 3 numbers", describe(node));
    Vector3 v;
    for (std::size_t k = 0; k < 3; ++k) {
      v[static_cast<int>(k)] = bounded(node[k], path + "[" + std::to_string(k) + "]", max_abs, unit);
    }
    return v;
  }

  Vector3 vec3(const YAML::Node& map, const std::string& path, const char* key, double max_abs,
               const char* unit) const {
    return vec3(require(map, path, key), join(path, key), max_abs, unit);
  }

  Vector3 optionalVec3(const YAML::Node& map, const std::string& path, const char* key, double max_abs,
                       const char* unit) const {
    const YAML::Node node = map[key];
    if (!node.IsDefined() || node.IsNull()) return Vector3::Zero();
    return vec3(node, join(path, key), max_abs, unit);
  }

  Vector3 nonNegativeVec3(const YAML::Node& map, const std::string& path, const char* key, bool required, double max,
                          const char* unit) const {
    const YAML::Node node = map[key];
    if (!required && (!node.IsDefined() || node.IsNull())) return Vector3::Zero();
    const Vector3 v = vec3(map, path, key, max, unit);
    for (int k = 0; k < 3; ++k) {
      if (v[k] < 0.0)
        fail(node[static_cast<std::size_t>(k)], join(path, key) + "[" + std::to_string(k) + "]", "must be >= 0",
             describe(node[static_cast<std::size_t>(k)]));
    }
    return v;
  }

  std::string string(const YAML::Node& map, const std::string& path, const char* key) const {
    const YAML::Node node = require(map, path, key);
    if (!node.IsScalar() || node.Scalar().empty()) fail(node, join(path, key), "expected a name", describe(node));
    return node.Scalar();
  }

  YAML::Node list(const YAML::Node& root, const char* key, bool required) const {
    const YAML::Node node = root[key];
    if (!node.IsDefined() || node.IsNull()) {
      if (required) fail(root, key, "required list missing", "nothing");
      return YAML::Node(YAML::NodeType::Sequence);
    }
    if (!node.IsSequence()) fail(node, key, "expected a list", describe(node));
    return node;
  }

 private:
  std::string file_;
};

// Body index of the name at map[key]; "ground" is the fixed frame where allowed.
int bodyOf(const Reader& reader, const VehicleModel& model, const YAML::Node& map, const std::string& path,
           const char* key, bool ground_allowed) {
  const std::string name = reader.string(map, path, key);
  for (int b = 0; b < model.nBodies(); ++b) {
    if (model.bodies()[static_cast<std::size_t>(b)].name == name) return b;
  }
  if (name == "ground") {
    if (ground_allowed) return kGround;
    reader.fail(map[key], join(path, key), "the ground cannot be used here", name);
  }
  reader.fail(map[key], join(path, key), "no body of that name is defined", name);
}

// Runs a model builder call, turning its std::runtime_error into a file error at path.
template <typename F>
void build(const Reader& reader, const YAML::Node& where, const std::string& path, F&& call) {
  try {
    call();
  } catch (const VehicleFileError&) {
    throw;
  } catch (const std::runtime_error& e) {
    reader.fail(where, path, e.what(), describe(where["name"]));
  }
}

}  // namespace

void loadVehicleInto(const std::string& path, VehicleModel& model) {
  const Reader reader(path);
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw VehicleFileError(path + ": cannot open the file");
  } catch (const YAML::ParserException& e) {
    std::ostringstream os;
    os << path << ":" << e.mark.line + 1 << ": YAML syntax error: " << e.msg;
    throw VehicleFileError(os.str());
  }
  if (const auto dup = core::findDuplicateKey(root)) {
    throw VehicleFileError(path + ": " + dup->field + ": " + dup->describe());
  }
  if (!root.IsMap()) reader.fail(root, "(top level)", "expected a map", describe(root));
  reader.checkKeys(root, "",
                   {"name", "description", "parameters", "gravity", "bodies", "load_points", "joints", "forces",
                    "measurement_points"});

  if (root["gravity"].IsDefined()) {
    const Vector3 g = reader.vec3(root, "", "gravity", kMaxGravity, "m/s^2");
    build(reader, root["gravity"], "gravity", [&] { model.setGravity(g); });
  }

  // Bodies.
  const YAML::Node bodies = reader.list(root, "bodies", true);
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const YAML::Node node = bodies[k];
    const std::string where = "bodies[" + std::to_string(k) + "]";
    reader.checkKeys(node, where, {"name", "mass", "centre_of_mass", "inertia", "products_of_inertia"});
    RigidBody body;
    body.name = reader.string(node, where, "name");
    for (const auto& b : model.bodies()) {
      if (b.name == body.name) reader.fail(node["name"], join(where, "name"), "body defined twice", body.name);
    }
    if (body.name == "ground") reader.fail(node["name"], join(where, "name"), "reserved name", body.name);
    body.mass = reader.number(node, where, "mass");
    if (!(body.mass > 0.0))
      reader.fail(node["mass"], join(where, "mass"), "mass must be > 0 kg", describe(node["mass"]));
    if (!(body.mass <= kMaxMass)) {
      reader.fail(node["mass"], join(where, "mass"), "mass must be <= " + formatNumber(kMaxMass) + " kg",
                  describe(node["mass"]));
    }
    body.r_reference = reader.vec3(node, where, "centre_of_mass", kMaxPosition, "m");
    const Vector3 principal = reader.vec3(node, where, "inertia", kMaxInertia, "kg m^2");
    for (int i = 0; i < 3; ++i) {
      if (!(principal[i] > 0.0)) {
        reader.fail(node["inertia"][static_cast<std::size_t>(i)],
                    join(where, "inertia") + "[" + std::to_string(i) + "]", "moment of inertia must be > 0 kg m^2",
                    describe(node["inertia"][static_cast<std::size_t>(i)]));
      }
      if (!(principal[i] >= kMinInertia)) {
        reader.fail(node["inertia"][static_cast<std::size_t>(i)],
                    join(where, "inertia") + "[" + std::to_string(i) + "]",
                    "moment of inertia must be >= " + formatNumber(kMinInertia) + " kg m^2",
                    describe(node["inertia"][static_cast<std::size_t>(i)]));
      }
    }
    const Vector3 products = reader.optionalVec3(node, where, "products_of_inertia", kMaxInertia, "kg m^2");
    body.inertia_in_body << principal[0], products[0], products[1], products[0], principal[1], products[2], products[1],
        products[2], principal[2];
    build(reader, node, where, [&] { model.addBody(body); });
  }

  // Load points.
  const YAML::Node points = reader.list(root, "load_points", false);
  for (std::size_t k = 0; k < points.size(); ++k) {
    const YAML::Node node = points[k];
    const std::string where = "load_points[" + std::to_string(k) + "]";
    reader.checkKeys(node, where, {"name", "body", "position"});
    const std::string name = reader.string(node, where, "name");
    const int body = bodyOf(reader, model, node, where, "body", false);
    const Vector3 p = reader.vec3(node, where, "position", kMaxPosition, "m");
    build(reader, node, where, [&] { model.addLoadPointAtWorld(name, body, p); });
  }

  // Measurement points (reported motion only, e.g. floor accelerometers).
  const YAML::Node measured = reader.list(root, "measurement_points", false);
  for (std::size_t k = 0; k < measured.size(); ++k) {
    const YAML::Node node = measured[k];
    const std::string where = "measurement_points[" + std::to_string(k) + "]";
    reader.checkKeys(node, where, {"name", "body", "position"});
    const std::string name = reader.string(node, where, "name");
    const int body = bodyOf(reader, model, node, where, "body", false);
    const Vector3 p = reader.vec3(node, where, "position", kMaxPosition, "m");
    build(reader, node, where, [&] { model.addMeasurementPointAtWorld(name, body, p); });
  }

  // Joints.
  std::set<std::string> joint_names;
  const YAML::Node joints = reader.list(root, "joints", false);
  for (std::size_t k = 0; k < joints.size(); ++k) {
    const YAML::Node node = joints[k];
    const std::string where = "joints[" + std::to_string(k) + "]";
    if (!node.IsMap()) reader.fail(node, where, "expected a map", describe(node));
    const std::string type = reader.string(node, where, "type");
    if (type == "revolute") {
      reader.checkKeys(node, where, {"name", "type", "body_i", "body_j", "position", "axis"});
    } else if (type == "spherical" || type == "fixed") {
      reader.checkKeys(node, where, {"name", "type", "body_i", "body_j", "position"});
    } else {
      reader.fail(node["type"], join(where, "type"), "unknown joint type (expected revolute, spherical or fixed)",
                  type);
    }
    const std::string name = reader.string(node, where, "name");
    if (!joint_names.insert(name).second) reader.fail(node["name"], join(where, "name"), "joint defined twice", name);
    const int body_i = bodyOf(reader, model, node, where, "body_i", false);
    const int body_j = bodyOf(reader, model, node, where, "body_j", true);
    if (body_i == body_j)
      reader.fail(node["body_j"], join(where, "body_j"), "a joint needs two different bodies",
                  describe(node["body_j"]));
    const Vector3 p = reader.vec3(node, where, "position", kMaxPosition, "m");
    if (type == "revolute") {
      const Vector3 axis = reader.vec3(node, where, "axis", kMaxAxisComponent, "");
      if (axis.norm() < 1e-12)
        reader.fail(node["axis"], join(where, "axis"), "axis must not be zero", describe(node["axis"]));
      build(reader, node, where, [&] { model.addRevoluteJointAt(name, body_i, body_j, p, axis.normalized()); });
    } else if (type == "spherical") {
      build(reader, node, where, [&] { model.addSphericalJointAt(name, body_i, body_j, p); });
    } else {
      build(reader, node, where, [&] { model.addFixedJointAt(name, body_i, body_j, p); });
    }
  }

  // Force elements.
  std::set<std::string> force_names;
  const YAML::Node forces = reader.list(root, "forces", false);
  for (std::size_t k = 0; k < forces.size(); ++k) {
    const YAML::Node node = forces[k];
    const std::string where = "forces[" + std::to_string(k) + "]";
    if (!node.IsMap()) reader.fail(node, where, "expected a map", describe(node));
    const std::string type = reader.string(node, where, "type");
    if (type == "bushing") {
      reader.checkKeys(node, where,
                       {"name", "type", "body_i", "body_j", "position", "stiffness", "damping", "preload",
                        "free_offset", "rotational_stiffness", "rotational_damping"});
    } else if (type == "point_to_point") {
      reader.checkKeys(node, where,
                       {"name", "type", "body_i", "body_j", "position_i", "position_j", "stiffness", "damping",
                        "free_length", "preload"});
    } else if (type == "bump_stop") {
      reader.checkKeys(node, where, {"name", "type", "body_i", "body_j", "position", "axis", "table"});
    } else {
      reader.fail(node["type"], join(where, "type"),
                  "unknown force type (expected bushing, point_to_point or bump_stop)", type);
    }
    const std::string name = reader.string(node, where, "name");
    if (!force_names.insert(name).second)
      reader.fail(node["name"], join(where, "name"), "force element defined twice", name);
    const int body_i = bodyOf(reader, model, node, where, "body_i", true);
    const int body_j = bodyOf(reader, model, node, where, "body_j", true);
    if (body_i == body_j)
      reader.fail(node["body_j"], join(where, "body_j"), "a force element needs two different bodies",
                  describe(node["body_j"]));
    if (type == "bushing") {
      Bushing::Parameters par;
      par.stiffness = reader.nonNegativeVec3(node, where, "stiffness", false, kMaxStiffness, "N/m");
      par.damping = reader.nonNegativeVec3(node, where, "damping", false, kMaxDamping, "N s/m");
      par.preload = reader.optionalVec3(node, where, "preload", kMaxForce, "N");
      par.free_offset = reader.optionalVec3(node, where, "free_offset", kMaxPosition, "m");
      par.rotational_stiffness =
          reader.nonNegativeVec3(node, where, "rotational_stiffness", false, kMaxStiffness, "N m/rad");
      par.rotational_damping =
          reader.nonNegativeVec3(node, where, "rotational_damping", false, kMaxDamping, "N m s/rad");
      const Vector3 p = reader.vec3(node, where, "position", kMaxPosition, "m");
      build(reader, node, where, [&] { model.addBushingAt(name, body_i, body_j, p, Matrix3::Identity(), par); });
    } else if (type == "point_to_point") {
      const Vector3 p_i = reader.vec3(node, where, "position_i", kMaxPosition, "m");
      const Vector3 p_j = reader.vec3(node, where, "position_j", kMaxPosition, "m");
      const double stiffness = reader.optionalBounded(node, where, "stiffness", 0.0, kMaxStiffness, "N/m");
      const double damping = reader.optionalBounded(node, where, "damping", 0.0, kMaxDamping, "N s/m");
      const double free_length = reader.optionalBounded(node, where, "free_length", -1.0, kMaxPosition, "m");
      const double preload = reader.optionalBounded(node, where, "preload", 0.0, kMaxForce, "N");
      if (stiffness < 0.0)
        reader.fail(node["stiffness"], join(where, "stiffness"), "must be >= 0", describe(node["stiffness"]));
      if (damping < 0.0)
        reader.fail(node["damping"], join(where, "damping"), "must be >= 0", describe(node["damping"]));
      if (node["free_length"].IsDefined() && free_length < 0.0) {
        reader.fail(node["free_length"], join(where, "free_length"), "must be >= 0", describe(node["free_length"]));
      }
      if ((p_j - p_i).norm() < 1e-9) {
        reader.fail(node["position_j"], join(where, "position_j"), "must differ from position_i",
                    describe(node["position_j"]));
      }
      build(reader, node, where,
            [&] { model.addPointToPointAt(name, body_i, body_j, p_i, p_j, stiffness, damping, free_length, preload); });
    } else {
      const Vector3 p = reader.vec3(node, where, "position", kMaxPosition, "m");
      const Vector3 axis = reader.vec3(node, where, "axis", kMaxAxisComponent, "");
      if (axis.norm() < 1e-12)
        reader.fail(node["axis"], join(where, "axis"), "axis must not be zero", describe(node["axis"]));
      const YAML::Node table = reader.require(node, where, "table");
      if (!table.IsSequence() || table.size() < 2) {
        reader.fail(table, join(where, "table"), "expected a list of >= 2 [deflection, force] rows", describe(table));
      }
      std::vector<double> deflections, magnitudes;
      for (std::size_t r = 0; r < table.size(); ++r) {
        const std::string row_path = join(where, "table") + "[" + std::to_string(r) + "]";
        const YAML::Node row = table[r];
        if (!row.IsSequence() || row.size() != 2)
          reader.fail(row, row_path, "expected [deflection, force]", describe(row));
        const double d = reader.bounded(row[0], row_path + "[0]", kMaxPosition, "m");
        const double f = reader.bounded(row[1], row_path + "[1]", kMaxForce, "N");
        if (r == 0 && (d < 0.0 || f != 0.0)) {
          reader.fail(row, row_path, "first row must be [clearance >= 0, 0]", describe(row));
        }
        if (r > 0 && !(d > deflections.back())) {
          reader.fail(row[0], row_path + "[0]", "deflection not increasing (after " + describe(table[r - 1][0]) + ")",
                      describe(row[0]));
        }
        if (r > 0 && f < magnitudes.back()) {
          reader.fail(row[1], row_path + "[1]", "force decreasing (after " + describe(table[r - 1][1]) + ")",
                      describe(row[1]));
        }
        deflections.push_back(d);
        magnitudes.push_back(f);
      }
      build(reader, node, where,
            [&] { model.addBumpStopAt(name, body_i, body_j, p, axis.normalized(), deflections, magnitudes); });
    }
  }
}

VehicleModel loadVehicleModel(const std::string& path) {
  VehicleModel model;
  loadVehicleInto(path, model);
  model.finalize();
  return model;
}

}  // namespace rail::vehicle
