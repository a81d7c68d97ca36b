#include "rail_vehicle_node/vehicle_loader.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <initializer_list>
#include <limits>
#include <set>
#include <sstream>
#include <utility>
#include <vector>

#include "rail_core/yaml_duplicates.hpp"

namespace rail::vehicle {
namespace {

std::string Describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter out;
  out << YAML::Flow << node;
  return out.c_str();
}

std::string Join(const std::string& path, const std::string& key) { return path.empty() ? key : path + "." + key; }

// Magnitude bounds of the vehicle data, refused above (never clamped). Far beyond any rail vehicle, they
// only catch mistyped or corrupted values that would make the integration fail.
constexpr double kMaxPosition = 1e3;        // m, |coordinate| of a position, offset, length or deflection
constexpr double kMaxForce = 1e8;           // N, |preload| or bump-stop force (a loaded axle: 2e5 N)
constexpr double kMaxStiffness = 1e12;      // N/m or N m/rad
constexpr double kMaxDamping = 1e12;        // N s/m or N m s/rad
constexpr double kMaxMass = 1e6;            // kg (a loaded coach: 6e4 kg)
constexpr double kMaxInertia = 1e8;         // kg m^2, |principal moment| or |product| (a carbody: 3e6)
// kg m^2, principal moment: 1 g at 1 mm from the axis. Below it the body's angular accelerations dwarf every
// other rate of the model (an axlebox: 10 kg m^2) and no integrator step resolves them.
constexpr double kMinInertia = 1e-6;
constexpr double kMaxGravity = 1e3;         // m/s^2, |component| of the gravity vector
constexpr double kMaxAxisComponent = 1e6;   // dimensionless, |component| of a direction before normalising

std::string Format(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  // "<file>: <path>: <what>, got <value> (line N)"
  [[noreturn]] void Fail(const YAML::Node& where, const std::string& path, const std::string& what,
                         const std::string& got) const {
    std::ostringstream os;
    os << file_ << ": " << path << ": " << what << ", got " << got;
    if (where.IsDefined() && where.Mark().line >= 0) os << " (line " << where.Mark().line + 1 << ")";
    throw VehicleFileError(os.str());
  }

  YAML::Node Require(const YAML::Node& map, const std::string& path, const char* key) const {
    const YAML::Node node = map[key];
    if (!node.IsDefined() || node.IsNull()) Fail(map, Join(path, key), "required key missing", "nothing");
    return node;
  }

  void CheckKeys(const YAML::Node& map, const std::string& path, std::initializer_list<const char*> allowed) const {
    if (!map.IsMap()) Fail(map, path, "expected a map", Describe(map));
    const std::set<std::string> keys(allowed.begin(), allowed.end());
    for (const auto& item : map) {
      const std::string key = item.first.as<std::string>();
      if (keys.count(key) == 0) {
        std::string list;
        for (const char* k : allowed) list += (list.empty() ? "" : ", ") + std::string(k);
        Fail(item.first, Join(path, key), "unknown key (expected one of " + list + ")", key);
      }
    }
  }

  double Number(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) Fail(node, path, "expected a number", Describe(node));
    double value = 0.0;
    try {
      value = node.as<double>();
    } catch (const YAML::Exception&) {
      Fail(node, path, "expected a number", Describe(node));
    }
    if (!std::isfinite(value)) Fail(node, path, "expected a finite number", Describe(node));
    return value;
  }

  // A finite number with |value| <= max_abs (unit names the unit of max_abs in the message).
  double Bounded(const YAML::Node& node, const std::string& path, double max_abs, const char* unit) const {
    const double value = Number(node, path);
    if (!(std::abs(value) <= max_abs)) {
      const std::string unit_text = *unit ? std::string(" ") + unit : std::string();
      Fail(node, path, "magnitude must be <= " + Format(max_abs) + unit_text, Describe(node));
    }
    return value;
  }

  double OptionalBounded(const YAML::Node& map, const std::string& path, const char* key, double fallback,
                         double max_abs, const char* unit) const {
    const YAML::Node node = map[key];
    if (!node.IsDefined() || node.IsNull()) return fallback;
    return Bounded(node, Join(path, key), max_abs, unit);
  }

  double Number(const YAML::Node& map, const std::string& path, const char* key) const {
    return Number(Require(map, path, key), Join(path, key));
  }

  // A list of 3 numbers, each with |component| <= max_abs (unit: the unit of max_abs).
  Vector3 Vec3(const YAML::Node& node, const std::string& path, double max_abs, const char* unit) const {
    if (!node.IsSequence() || node.size() != 3) Fail(node, path, "expected a list of 3 numbers", Describe(node));
    Vector3 v;
    for (std::size_t k = 0; k < 3; ++k) {
      v[static_cast<int>(k)] = Bounded(node[k], path + "[" + std::to_string(k) + "]", max_abs, unit);
    }
    return v;
  }

  Vector3 Vec3(const YAML::Node& map, const std::string& path, const char* key, double max_abs,
               const char* unit) const {
    return Vec3(Require(map, path, key), Join(path, key), max_abs, unit);
  }

  Vector3 OptionalVec3(const YAML::Node& map, const std::string& path, const char* key, double max_abs,
                       const char* unit) const {
    const YAML::Node node = map[key];
    if (!node.IsDefined() || node.IsNull()) return Vector3::Zero();
    return Vec3(node, Join(path, key), max_abs, unit);
  }

  Vector3 NonNegativeVec3(const YAML::Node& map, const std::string& path, const char* key, bool required,
                          double max, const char* unit) const {
    const YAML::Node node = map[key];
    if (!required && (!node.IsDefined() || node.IsNull())) return Vector3::Zero();
    const Vector3 v = Vec3(map, path, key, max, unit);
    for (int k = 0; k < 3; ++k) {
      if (v[k] < 0.0) Fail(node[static_cast<std::size_t>(k)], Join(path, key) + "[" + std::to_string(k) + "]",
                           "must be >= 0", Describe(node[static_cast<std::size_t>(k)]));
    }
    return v;
  }

  std::string String(const YAML::Node& map, const std::string& path, const char* key) const {
    const YAML::Node node = Require(map, path, key);
    if (!node.IsScalar() || node.Scalar().empty()) Fail(node, Join(path, key), "expected a name", Describe(node));
    return node.Scalar();
  }

  YAML::Node List(const YAML::Node& root, const char* key, bool required) const {
    const YAML::Node node = root[key];
    if (!node.IsDefined() || node.IsNull()) {
      if (required) Fail(root, key, "required list missing", "nothing");
      return YAML::Node(YAML::NodeType::Sequence);
    }
    if (!node.IsSequence()) Fail(node, key, "expected a list", Describe(node));
    return node;
  }

 private:
  std::string file_;
};

// Body index of the name at map[key]; "ground" is the fixed frame where allowed.
int BodyOf(const Reader& reader, const VehicleModel& model, const YAML::Node& map, const std::string& path,
           const char* key, bool ground_allowed) {
  const std::string name = reader.String(map, path, key);
  for (int b = 0; b < model.n_bodies(); ++b) {
    if (model.bodies()[static_cast<std::size_t>(b)].name == name) return b;
  }
  if (name == "ground") {
    if (ground_allowed) return kGround;
    reader.Fail(map[key], Join(path, key), "the ground cannot be used here", name);
  }
  reader.Fail(map[key], Join(path, key), "no body of that name is defined", name);
}

// Runs a model builder call, turning its std::runtime_error into a file error at path.
template <typename F>
void Build(const Reader& reader, const YAML::Node& where, const std::string& path, F&& call) {
  try {
    call();
  } catch (const VehicleFileError&) {
    throw;
  } catch (const std::runtime_error& e) {
    reader.Fail(where, path, e.what(), Describe(where["name"]));
  }
}

}  // namespace

void LoadVehicleInto(const std::string& path, VehicleModel& model) {
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
  if (const auto dup = core::find_duplicate_key(root)) {
    throw VehicleFileError(path + ": " + dup->field + ": " + dup->describe());
  }
  if (!root.IsMap()) reader.Fail(root, "(top level)", "expected a map", Describe(root));
  reader.CheckKeys(root, "", {"name", "description", "parameters", "gravity", "bodies", "load_points", "joints", "forces",
                                  "measurement_points"});

  if (root["gravity"].IsDefined()) {
    const Vector3 g = reader.Vec3(root, "", "gravity", kMaxGravity, "m/s^2");
    Build(reader, root["gravity"], "gravity", [&] { model.SetGravity(g); });
  }

  // Bodies.
  const YAML::Node bodies = reader.List(root, "bodies", true);
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const YAML::Node node = bodies[k];
    const std::string where = "bodies[" + std::to_string(k) + "]";
    reader.CheckKeys(node, where, {"name", "mass", "centre_of_mass", "inertia", "products_of_inertia"});
    RigidBody body;
    body.name = reader.String(node, where, "name");
    for (const auto& b : model.bodies()) {
      if (b.name == body.name) reader.Fail(node["name"], Join(where, "name"), "body defined twice", body.name);
    }
    if (body.name == "ground") reader.Fail(node["name"], Join(where, "name"), "reserved name", body.name);
    body.mass = reader.Number(node, where, "mass");
    if (!(body.mass > 0.0)) reader.Fail(node["mass"], Join(where, "mass"), "mass must be > 0 kg", Describe(node["mass"]));
    if (!(body.mass <= kMaxMass)) {
      reader.Fail(node["mass"], Join(where, "mass"), "mass must be <= " + Format(kMaxMass) + " kg", Describe(node["mass"]));
    }
    body.r_reference = reader.Vec3(node, where, "centre_of_mass", kMaxPosition, "m");
    const Vector3 principal = reader.Vec3(node, where, "inertia", kMaxInertia, "kg m^2");
    for (int i = 0; i < 3; ++i) {
      if (!(principal[i] > 0.0)) {
        reader.Fail(node["inertia"][static_cast<std::size_t>(i)], Join(where, "inertia") + "[" + std::to_string(i) + "]",
                    "moment of inertia must be > 0 kg m^2", Describe(node["inertia"][static_cast<std::size_t>(i)]));
      }
      if (!(principal[i] >= kMinInertia)) {
        reader.Fail(node["inertia"][static_cast<std::size_t>(i)], Join(where, "inertia") + "[" + std::to_string(i) + "]",
                    "moment of inertia must be >= " + Format(kMinInertia) + " kg m^2",
                    Describe(node["inertia"][static_cast<std::size_t>(i)]));
      }
    }
    const Vector3 products = reader.OptionalVec3(node, where, "products_of_inertia", kMaxInertia, "kg m^2");
    body.inertia_in_body << principal[0], products[0], products[1],
                            products[0], principal[1], products[2],
                            products[1], products[2], principal[2];
    Build(reader, node, where, [&] { model.AddBody(body); });
  }

  // Load points.
  const YAML::Node points = reader.List(root, "load_points", false);
  for (std::size_t k = 0; k < points.size(); ++k) {
    const YAML::Node node = points[k];
    const std::string where = "load_points[" + std::to_string(k) + "]";
    reader.CheckKeys(node, where, {"name", "body", "position"});
    const std::string name = reader.String(node, where, "name");
    const int body = BodyOf(reader, model, node, where, "body", false);
    const Vector3 p = reader.Vec3(node, where, "position", kMaxPosition, "m");
    Build(reader, node, where, [&] { model.AddLoadPointAtWorld(name, body, p); });
  }

  // Measurement points (reported motion only, e.g. floor accelerometers).
  const YAML::Node measured = reader.List(root, "measurement_points", false);
  for (std::size_t k = 0; k < measured.size(); ++k) {
    const YAML::Node node = measured[k];
    const std::string where = "measurement_points[" + std::to_string(k) + "]";
    reader.CheckKeys(node, where, {"name", "body", "position"});
    const std::string name = reader.String(node, where, "name");
    const int body = BodyOf(reader, model, node, where, "body", false);
    const Vector3 p = reader.Vec3(node, where, "position", kMaxPosition, "m");
    Build(reader, node, where, [&] { model.AddMeasurementPointAtWorld(name, body, p); });
  }

  // Joints.
  std::set<std::string> joint_names;
  const YAML::Node joints = reader.List(root, "joints", false);
  for (std::size_t k = 0; k < joints.size(); ++k) {
    const YAML::Node node = joints[k];
    const std::string where = "joints[" + std::to_string(k) + "]";
    if (!node.IsMap()) reader.Fail(node, where, "expected a map", Describe(node));
    const std::string type = reader.String(node, where, "type");
    if (type == "revolute") {
      reader.CheckKeys(node, where, {"name", "type", "body_i", "body_j", "position", "axis"});
    } else if (type == "spherical" || type == "fixed") {
      reader.CheckKeys(node, where, {"name", "type", "body_i", "body_j", "position"});
    } else {
      reader.Fail(node["type"], Join(where, "type"), "unknown joint type (expected revolute, spherical or fixed)", type);
    }
    const std::string name = reader.String(node, where, "name");
    if (!joint_names.insert(name).second) reader.Fail(node["name"], Join(where, "name"), "joint defined twice", name);
    const int body_i = BodyOf(reader, model, node, where, "body_i", false);
    const int body_j = BodyOf(reader, model, node, where, "body_j", true);
    if (body_i == body_j) reader.Fail(node["body_j"], Join(where, "body_j"), "a joint needs two different bodies",
                                      Describe(node["body_j"]));
    const Vector3 p = reader.Vec3(node, where, "position", kMaxPosition, "m");
    if (type == "revolute") {
      const Vector3 axis = reader.Vec3(node, where, "axis", kMaxAxisComponent, "");
      if (axis.norm() < 1e-12) reader.Fail(node["axis"], Join(where, "axis"), "axis must not be zero", Describe(node["axis"]));
      Build(reader, node, where, [&] { model.AddRevoluteJointAt(name, body_i, body_j, p, axis.normalized()); });
    } else if (type == "spherical") {
      Build(reader, node, where, [&] { model.AddSphericalJointAt(name, body_i, body_j, p); });
    } else {
      Build(reader, node, where, [&] { model.AddFixedJointAt(name, body_i, body_j, p); });
    }
  }

  // Force elements.
  std::set<std::string> force_names;
  const YAML::Node forces = reader.List(root, "forces", false);
  for (std::size_t k = 0; k < forces.size(); ++k) {
    const YAML::Node node = forces[k];
    const std::string where = "forces[" + std::to_string(k) + "]";
    if (!node.IsMap()) reader.Fail(node, where, "expected a map", Describe(node));
    const std::string type = reader.String(node, where, "type");
    if (type == "bushing") {
      reader.CheckKeys(node, where, {"name", "type", "body_i", "body_j", "position", "stiffness", "damping", "preload",
                                     "free_offset", "rotational_stiffness", "rotational_damping"});
    } else if (type == "point_to_point") {
      reader.CheckKeys(node, where, {"name", "type", "body_i", "body_j", "position_i", "position_j", "stiffness",
                                     "damping", "free_length", "preload"});
    } else if (type == "bump_stop") {
      reader.CheckKeys(node, where, {"name", "type", "body_i", "body_j", "position", "axis", "table"});
    } else {
      reader.Fail(node["type"], Join(where, "type"),
                  "unknown force type (expected bushing, point_to_point or bump_stop)", type);
    }
    const std::string name = reader.String(node, where, "name");
    if (!force_names.insert(name).second) reader.Fail(node["name"], Join(where, "name"), "force element defined twice", name);
    const int body_i = BodyOf(reader, model, node, where, "body_i", true);
    const int body_j = BodyOf(reader, model, node, where, "body_j", true);
    if (body_i == body_j) reader.Fail(node["body_j"], Join(where, "body_j"), "a force element needs two different bodies",
                                      Describe(node["body_j"]));
    if (type == "bushing") {
      Bushing::Parameters par;
      par.stiffness = reader.NonNegativeVec3(node, where, "stiffness", false, kMaxStiffness, "N/m");
      par.damping = reader.NonNegativeVec3(node, where, "damping", false, kMaxDamping, "N s/m");
      par.preload = reader.OptionalVec3(node, where, "preload", kMaxForce, "N");
      par.free_offset = reader.OptionalVec3(node, where, "free_offset", kMaxPosition, "m");
      par.rotational_stiffness =
          reader.NonNegativeVec3(node, where, "rotational_stiffness", false, kMaxStiffness, "N m/rad");
      par.rotational_damping = reader.NonNegativeVec3(node, where, "rotational_damping", false, kMaxDamping, "N m s/rad");
      const Vector3 p = reader.Vec3(node, where, "position", kMaxPosition, "m");
      Build(reader, node, where, [&] { model.AddBushingAt(name, body_i, body_j, p, Matrix3::Identity(), par); });
    } else if (type == "point_to_point") {
      const Vector3 p_i = reader.Vec3(node, where, "position_i", kMaxPosition, "m");
      const Vector3 p_j = reader.Vec3(node, where, "position_j", kMaxPosition, "m");
      const double stiffness = reader.OptionalBounded(node, where, "stiffness", 0.0, kMaxStiffness, "N/m");
      const double damping = reader.OptionalBounded(node, where, "damping", 0.0, kMaxDamping, "N s/m");
      const double free_length = reader.OptionalBounded(node, where, "free_length", -1.0, kMaxPosition, "m");
      const double preload = reader.OptionalBounded(node, where, "preload", 0.0, kMaxForce, "N");
      if (stiffness < 0.0) reader.Fail(node["stiffness"], Join(where, "stiffness"), "must be >= 0", Describe(node["stiffness"]));
      if (damping < 0.0) reader.Fail(node["damping"], Join(where, "damping"), "must be >= 0", Describe(node["damping"]));
      if (node["free_length"].IsDefined() && free_length < 0.0) {
        reader.Fail(node["free_length"], Join(where, "free_length"), "must be >= 0", Describe(node["free_length"]));
      }
      if ((p_j - p_i).norm() < 1e-9) {
        reader.Fail(node["position_j"], Join(where, "position_j"), "must differ from position_i", Describe(node["position_j"]));
      }
      Build(reader, node, where,
            [&] { model.AddPointToPointAt(name, body_i, body_j, p_i, p_j, stiffness, damping, free_length, preload); });
    } else {
      const Vector3 p = reader.Vec3(node, where, "position", kMaxPosition, "m");
      const Vector3 axis = reader.Vec3(node, where, "axis", kMaxAxisComponent, "");
      if (axis.norm() < 1e-12) reader.Fail(node["axis"], Join(where, "axis"), "axis must not be zero", Describe(node["axis"]));
      const YAML::Node table = reader.Require(node, where, "table");
      if (!table.IsSequence() || table.size() < 2) {
        reader.Fail(table, Join(where, "table"), "expected a list of >= 2 [deflection, force] rows", Describe(table));
      }
      std::vector<double> deflections, magnitudes;
      for (std::size_t r = 0; r < table.size(); ++r) {
        const std::string row_path = Join(where, "table") + "[" + std::to_string(r) + "]";
        const YAML::Node row = table[r];
        if (!row.IsSequence() || row.size() != 2) reader.Fail(row, row_path, "expected [deflection, force]", Describe(row));
        const double d = reader.Bounded(row[0], row_path + "[0]", kMaxPosition, "m");
        const double f = reader.Bounded(row[1], row_path + "[1]", kMaxForce, "N");
        if (r == 0 && (d < 0.0 || f != 0.0)) {
          reader.Fail(row, row_path, "first row must be [clearance >= 0, 0]", Describe(row));
        }
        if (r > 0 && !(d > deflections.back())) {
          reader.Fail(row[0], row_path + "[0]", "deflection not increasing (after " + Describe(table[r - 1][0]) + ")",
                      Describe(row[0]));
        }
        if (r > 0 && f < magnitudes.back()) {
          reader.Fail(row[1], row_path + "[1]", "force decreasing (after " + Describe(table[r - 1][1]) + ")",
                      Describe(row[1]));
        }
        deflections.push_back(d);
        magnitudes.push_back(f);
      }
      Build(reader, node, where, [&] {
        model.AddBumpStopAt(name, body_i, body_j, p, axis.normalized(), deflections, magnitudes);
      });
    }
  }
}

VehicleModel LoadVehicleModel(const std::string& path) {
  VehicleModel model;
  LoadVehicleInto(path, model);
  model.Finalize();
  return model;
}

}  // namespace rail::vehicle
