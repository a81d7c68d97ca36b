// Readers and writers of profile files: plain "y z" text, MiniProf text export (.ban / .whl) and
// SIMPACK profiles (.prr / .prw). Format conventions are described in doc/profiles.md.
#include "rail_contact/format.hpp"
#include "rail_contact/profile.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>

namespace rail {
namespace contact {

ProfileFileError::ProfileFileError(const std::string& file, int line, const std::string& what)
    : std::runtime_error(file + ":" + std::to_string(line) + ": " + what), file_(file), line_(line) {}

namespace {

constexpr double kMonotonicTolerance = 0.05e-3;  // accepted step back of the lateral coordinate, m
// Largest accepted |y| and |z| of a profile point, m (after unit conversion): a wheel or rail profile
// spans about 0.15 m, so a point beyond 1 m is a corrupted or mistyped value.
constexpr double kMaxCoordinate = 1.0;

std::string trim(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

std::string lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Parses a whole token as a finite double (a leading '+' is accepted).
bool parseDouble(const std::string& token, double& value) {
  const char* first = token.data();
  const char* last = token.data() + token.size();
  if (first != last && *first == '+') ++first;
  if (first == last) return false;
  const auto res = std::from_chars(first, last, value);
  return res.ec == std::errc() && res.ptr == last && std::isfinite(value);
}

// Splits on blanks, tabs and commas.
std::vector<std::string> splitTokens(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : line) {
    if (std::isspace(static_cast<unsigned char>(c)) || c == ',') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

std::vector<double> parseNumbers(const std::string& file, int line, const std::vector<std::string>& tokens) {
  std::vector<double> v(tokens.size());
  for (size_t i = 0; i < tokens.size(); ++i)
    if (!parseDouble(tokens[i], v[i])) throw ProfileFileError(file, line, "non-numeric value '" + tokens[i] + "'");
  return v;
}

// Point read from a file, in file units and axes, with its line number.
struct RawPoint {
  double y, z;
  int line;
};

std::ifstream openOrThrow(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ProfileFileError(path, 0, "cannot open file");
  return in;
}

// Checks the point list: enough points, no repeated point, lateral coordinate monotonic. A step back
// of at most tol (file units; 0.05 mm) behind the furthest value so far is accepted: a tilted rail's
// gauge face below the corner, or measurement noise on a vertical face, may lean back slightly.
// axis_name names the lateral column.
void checkPoints(const std::string& file, int last_line, const std::vector<RawPoint>& pts, const std::string& axis_name,
                 double tol) {
  if (pts.size() < 4)
    throw ProfileFileError(file, last_line, "too few points (" + std::to_string(pts.size()) + ", need at least 4)");
  int dir = 0;
  double extreme = pts.front().y;
  for (size_t i = 1; i < pts.size(); ++i) {
    const RawPoint& a = pts[i - 1];
    const RawPoint& b = pts[i];
    if (a.y == b.y && a.z == b.z)
      throw ProfileFileError(file, b.line, "repeated point (" + formatNumber(b.y) + " " + formatNumber(b.z) + ")");
    if (dir == 0) {
      if (std::abs(b.y - pts.front().y) > tol) dir = b.y > pts.front().y ? 1 : -1;
      extreme = dir >= 0 ? std::max(extreme, b.y) : std::min(extreme, b.y);
      continue;
    }
    if (dir * (extreme - b.y) > tol)
      throw ProfileFileError(file, b.line,
                             axis_name + (dir > 0 ? " not increasing (" : " not decreasing (") + formatNumber(b.y) +
                                 " after " + formatNumber(extreme) + ")");
    extreme = dir > 0 ? std::max(extreme, b.y) : std::min(extreme, b.y);
  }
}

// Refuses a point with |y| or |z| beyond kMaxCoordinate; scale converts file units to m. Names the
// point's line and the value as written in the file (unit_name: the file's length unit).
void checkBounds(const std::string& file, const std::vector<RawPoint>& pts, double scale, const std::string& y_name,
                 const std::string& z_name, const std::string& unit_name) {
  for (const RawPoint& p : pts) {
    const bool bad_y = !(std::abs(p.y * scale) <= kMaxCoordinate);
    if (bad_y || !(std::abs(p.z * scale) <= kMaxCoordinate))
      throw ProfileFileError(file, p.line,
                             (bad_y ? y_name + " = " + formatNumber(p.y) : z_name + " = " + formatNumber(p.z)) + " " +
                                 unit_name + " out of range (|" + y_name + "|, |" + z_name + "| must be at most " +
                                 formatNumber(kMaxCoordinate) + " m)");
  }
}

ProfilePoints applyOptions(ProfilePoints pts, const ProfileFileOptions& o) {
  for (Eigen::Vector2d& p : pts) {
    if (o.mirror_y) p.x() = -p.x();
    if (o.mirror_z) p.y() = -p.y();
    p += Eigen::Vector2d(o.shift_y, o.shift_z);
  }
  return pts;
}

std::string extension(const std::string& path) {
  const size_t slash = path.find_last_of("/\\");
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  return lower(path.substr(dot));
}

}  // namespace

// ----------------------------------------------------------------------------------------------------

ProfilePoints readPlainProfile(const std::string& path, const ProfileFileOptions& options) {
  std::ifstream in = openOrThrow(path);
  std::vector<RawPoint> pts;
  std::string line;
  int iline = 0;
  int units = 0;  // 0: by rule, 1: mm, 2: m
  while (std::getline(in, line)) {
    ++iline;
    const size_t hash = line.find('#');
    if (hash != std::string::npos) {
      const std::string comment = lower(trim(line.substr(hash + 1)));
      if (comment.rfind("units:", 0) == 0) {
        const std::string u = trim(comment.substr(6));
        if (u == "mm")
          units = 1;
        else if (u == "m")
          units = 2;
        else
          throw ProfileFileError(path, iline, "unknown units '" + u + "' (expected mm or m)");
      }
      line = line.substr(0, hash);
    }
    const std::vector<std::string> tok = splitTokens(line);
    if (tok.empty()) continue;
    if (tok.size() != 2)
      throw ProfileFileError(path, iline,
                             "wrong column count (" + std::to_string(tok.size()) + " values, expected 2: y z)");
    const std::vector<double> v = parseNumbers(path, iline, tok);
    pts.push_back({v[0], v[1], iline});
  }
  if (units == 0) {
    double max_abs = 0.0;
    for (const RawPoint& p : pts) max_abs = std::max({max_abs, std::abs(p.y), std::abs(p.z)});
    units = max_abs > 1.0 ? 1 : 2;
  }
  const double scale = units == 1 ? 1e-3 : 1.0;
  checkBounds(path, pts, scale, "y", "z", units == 1 ? "mm" : "m");
  checkPoints(path, iline, pts, "y", kMonotonicTolerance / scale);
  ProfilePoints out;
  out.reserve(pts.size());
  for (const RawPoint& p : pts) out.emplace_back(p.y * scale, p.z * scale);
  return applyOptions(out, options);
}

ProfilePoints readMiniProfProfile(const std::string& path, const ProfileFileOptions& options) {
  std::ifstream in = openOrThrow(path);
  std::vector<std::string> columns = {"X", "Y"};
  int col_x = 0, col_y = 1;
  std::vector<RawPoint> pts;
  std::string line;
  int iline = 0;
  while (std::getline(in, line)) {
    ++iline;
    const std::string t = trim(line);
    if (t.empty()) continue;
    if (t[0] == '"') continue;  // flagged point, excluded from the profile
    if (t[0] == '[') throw ProfileFileError(path, iline, "sectioned MiniProf file not supported ('" + t + "')");
    const size_t eq = t.find('=');
    if (eq != std::string::npos) {
      const std::string key = trim(t.substr(0, eq));
      if (lower(key) == "columndef") {
        columns.clear();
        for (const std::string& c : splitTokens(t.substr(eq + 1))) columns.push_back(c);
        const auto ix = std::find(columns.begin(), columns.end(), "X");
        const auto iy = std::find(columns.begin(), columns.end(), "Y");
        if (ix == columns.end() || iy == columns.end())
          throw ProfileFileError(path, iline, "ColumnDef must name columns X and Y ('" + trim(t.substr(eq + 1)) + "')");
        col_x = static_cast<int>(ix - columns.begin());
        col_y = static_cast<int>(iy - columns.begin());
      }
      continue;
    }
    const std::vector<std::string> tok = splitTokens(t);
    if (tok.size() != columns.size())
      throw ProfileFileError(path, iline,
                             "wrong column count (" + std::to_string(tok.size()) + " values, ColumnDef has " +
                                 std::to_string(columns.size()) + ")");
    const std::vector<double> v = parseNumbers(path, iline, tok);
    pts.push_back({v[col_x], v[col_y], iline});
  }
  checkBounds(path, pts, 1e-3, "X", "Y", "mm");
  checkPoints(path, iline, pts, "X", kMonotonicTolerance * 1e3);
  ProfilePoints out;
  out.reserve(pts.size());
  for (const RawPoint& p : pts) out.emplace_back(p.y * 1e-3, -p.z * 1e-3);  // X -> y, Y (down) -> -z
  return applyOptions(out, options);
}

ProfilePoints readSimpackProfile(const std::string& path, const ProfileFileOptions& options, int* type_out) {
  std::ifstream in = openOrThrow(path);
  enum Block { None, Header, Spline, Point };
  Block block = None;
  bool seen_spline = false, seen_points = false;
  int type = -1;
  // Spline-block keywords with their defaults.
  double dist_min = 0.0, shift_y = 0.0, shift_z = 0.0, rotate = 0.0;
  double bound_y_min = 1.0, bound_y_max = 0.0, bound_z_min = 1.0, bound_z_max = 0.0;
  double mirror_y = 0.0, mirror_z = 0.0, inversion = 0.0, len_f = 1.0, ang_f = 1.0;
  std::vector<RawPoint> pts;
  std::string line;
  int iline = 0;
  while (std::getline(in, line)) {
    ++iline;
    // Strip comments ('!' outside single-quoted strings).
    bool quoted = false;
    for (size_t i = 0; i < line.size(); ++i) {
      if (line[i] == '\'') quoted = !quoted;
      if (line[i] == '!' && !quoted) {
        line.resize(i);
        break;
      }
    }
    const std::string t = trim(line);
    if (t.empty()) continue;
    const std::string tl = lower(t);
    if (tl == "header.begin" || tl == "spline.begin" || tl == "point.begin") {
      const Block want = tl == "header.begin" ? Header : (tl == "spline.begin" ? Spline : Point);
      const Block need = want == Point ? Spline : None;
      if (block != need) throw ProfileFileError(path, iline, "unexpected '" + t + "'");
      block = want;
      if (want == Spline) seen_spline = true;
      if (want == Point) seen_points = true;
      continue;
    }
    if (tl == "header.end" || tl == "spline.end" || tl == "point.end") {
      const Block have = tl == "header.end" ? Header : (tl == "spline.end" ? Spline : Point);
      if (block != have) throw ProfileFileError(path, iline, "unexpected '" + t + "'");
      block = have == Point ? Spline : None;
      continue;
    }
    const size_t eq = t.find('=');
    if (eq != std::string::npos) {
      if (block != Header && block != Spline)
        throw ProfileFileError(path, iline, "keyword outside header/spline block ('" + t + "')");
      const std::string key = lower(trim(t.substr(0, eq)));
      const std::string val = trim(t.substr(eq + 1));
      auto num = [&](double& target) {
        if (!parseDouble(val, target))
          throw ProfileFileError(path, iline, "non-numeric value '" + val + "' for " + key);
      };
      if (block == Header) {
        if (key == "type") {
          double v = 0.0;
          num(v);
          if (v != 0.0 && v != 1.0) throw ProfileFileError(path, iline, "type must be 0 or 1 ('" + val + "')");
          type = static_cast<int>(v);
        } else if (key == "version") {
          double v = 0.0;
          num(v);
        }
        continue;
      }
      if (key == "point.dist.min")
        num(dist_min);
      else if (key == "shift.y")
        num(shift_y);
      else if (key == "shift.z")
        num(shift_z);
      else if (key == "rotate")
        num(rotate);
      else if (key == "bound.y.min")
        num(bound_y_min);
      else if (key == "bound.y.max")
        num(bound_y_max);
      else if (key == "bound.z.min")
        num(bound_z_min);
      else if (key == "bound.z.max")
        num(bound_z_max);
      else if (key == "mirror.y")
        num(mirror_y);
      else if (key == "mirror.z")
        num(mirror_z);
      else if (key == "inversion")
        num(inversion);
      else if (key == "units.len.f") {
        num(len_f);
        if (!(len_f > 0.0)) throw ProfileFileError(path, iline, "units.len.f must be positive ('" + val + "')");
      } else if (key == "units.ang.f") {
        num(ang_f);
        if (!(ang_f > 0.0)) throw ProfileFileError(path, iline, "units.ang.f must be positive ('" + val + "')");
      }
      // other keywords (approx.smooth, file, comment, type, units.len, ...) carry no geometry
      continue;
    }
    if (block != Point) throw ProfileFileError(path, iline, "data outside point.begin/point.end ('" + t + "')");
    const std::vector<std::string> tok = splitTokens(t);
    if (tok.size() != 2 && tok.size() != 3)
      throw ProfileFileError(path, iline,
                             "wrong column count (" + std::to_string(tok.size()) + " values, expected y z [weight])");
    const std::vector<double> v = parseNumbers(path, iline, tok);
    pts.push_back({v[0], v[1], iline});
  }
  if (block != None) throw ProfileFileError(path, iline, "file ends inside a block");
  if (!seen_spline || !seen_points) throw ProfileFileError(path, iline, "no spline/point block");
  const std::string len_unit =
      len_f == 1e3 ? "mm" : (len_f == 1.0 ? "m" : "(units.len.f = " + formatNumber(len_f) + ")");
  checkBounds(path, pts, 1.0 / len_f, "y", "z", len_unit);
  checkPoints(path, iline, pts, "y", kMonotonicTolerance * len_f);

  // Spline-block modifications, in SIMPACK's order (file units).
  std::vector<Eigen::Vector2d> p;
  for (const RawPoint& r : pts) {
    if (dist_min > 0.0 && !p.empty() && std::abs(r.y - p.back().x()) <= dist_min) continue;
    p.emplace_back(r.y, r.z);
  }
  const double ang = rotate / ang_f, c = std::cos(ang), s = std::sin(ang);
  std::vector<Eigen::Vector2d> q;
  for (Eigen::Vector2d v : p) {
    v += Eigen::Vector2d(shift_y, shift_z);
    v = Eigen::Vector2d(c * v.x() - s * v.y(), s * v.x() + c * v.y());
    if (bound_y_min < bound_y_max && (v.x() < bound_y_min || v.x() > bound_y_max)) continue;
    if (bound_z_min < bound_z_max) v.y() = std::clamp(v.y(), bound_z_min, bound_z_max);
    if (mirror_y != 0.0) v.x() = -v.x();
    if (mirror_z != 0.0) v.y() = -v.y();
    q.push_back(v);
  }
  if (inversion != 0.0) std::reverse(q.begin(), q.end());
  if (q.size() < 4)
    throw ProfileFileError(
        path, iline,
        "too few points after the spline-block modifications (" + std::to_string(q.size()) + ", need at least 4)");
  ProfilePoints out;
  out.reserve(q.size());
  for (const Eigen::Vector2d& v : q)
    out.emplace_back(-v.x() / len_f, -v.y() / len_f);  // y field -> gauge, z down -> up
  if (type_out) *type_out = type;
  return applyOptions(out, options);
}

ProfilePoints readProfilePoints(const std::string& path, const ProfileFileOptions& options) {
  const std::string ext = extension(path);
  if (ext == ".ban" || ext == ".whl") return readMiniProfProfile(path, options);
  if (ext == ".prr" || ext == ".prw") return readSimpackProfile(path, options);
  return readPlainProfile(path, options);
}

ProfilePoints orderByIncreasingY(ProfilePoints pts) {
  if (!pts.empty() && pts.back().x() < pts.front().x()) std::reverse(pts.begin(), pts.end());
  return pts;
}

// A curve that cannot be built from a file's points is reported against the file as a whole (line 0).
ProfileCurve loadRailProfile(const std::string& path, const ProfileFileOptions& options,
                             const ProfileCurveOptions& curve_options, double inclination) {
  const ProfilePoints points = orderByIncreasingY(readProfilePoints(path, options));
  try {
    return ProfileCurve(inclination == 0.0 ? points : tiltProfile(points, inclination), SolidSide::Right,
                        curve_options);
  } catch (const std::exception& e) {
    throw ProfileFileError(path, 0, std::string("rail profile: ") + e.what());
  }
}

WheelProfile loadWheelProfile(const std::string& path, const ProfileFileOptions& options, double split_angle,
                              const ProfileCurveOptions& curve_options) {
  const ProfilePoints points = orderByIncreasingY(readProfilePoints(path, options));
  try {
    return makeWheelProfile(points, split_angle, curve_options);
  } catch (const std::exception& e) {
    throw ProfileFileError(path, 0, std::string("wheel profile: ") + e.what());
  }
}

// ----------------------------------------------------------------------------------------------------

namespace {
std::ofstream createOrThrow(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path + ": cannot open file for writing");
  return out;
}
void closeOrThrow(std::ofstream& out, const std::string& path) {
  out.close();
  if (!out) throw std::runtime_error(path + ": write failed");
}
// A coordinate as the profile files write it (SIMPACK's fixed-width %+.15e, read back exactly): file
// data, not message text, so not formatNumber.
std::string fileNumber(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%+.15e", v);
  return buf;
}
std::string baseName(const std::string& path) {
  const size_t slash = path.find_last_of("/\\");
  return slash == std::string::npos ? path : path.substr(slash + 1);
}
}  // namespace

void writePlainProfile(const std::string& path, const ProfilePoints& points_yz, const std::string& comment) {
  std::ofstream out = createOrThrow(path);
  if (!comment.empty()) out << "# " << comment << "\n";
  out << "# units: mm\n# y z\n";
  for (const Eigen::Vector2d& p : points_yz) out << fileNumber(p.x() * 1e3) << " " << fileNumber(p.y() * 1e3) << "\n";
  closeOrThrow(out, path);
}

void writeMiniProfProfile(const std::string& path, const ProfilePoints& points_yz) {
  std::ofstream out = createOrThrow(path);
  out << "Filename=" << baseName(path) << "\n";
  out << "XYPoints=" << points_yz.size() << "\n";
  out << "ColumnDef=X,Y\n\n";
  for (const Eigen::Vector2d& p : points_yz) out << fileNumber(p.x() * 1e3) << "\t" << fileNumber(-p.y() * 1e3) << "\n";
  closeOrThrow(out, path);
}

void writeSimpackProfile(const std::string& path, const ProfilePoints& points_yz, int type,
                         const std::string& comment) {
  if (type != 0 && type != 1) throw std::invalid_argument("writeSimpackProfile: type must be 0 (rail) or 1 (wheel)");
  std::string safe_comment = comment;
  std::replace(safe_comment.begin(), safe_comment.end(), '\'', '"');
  std::replace(safe_comment.begin(), safe_comment.end(), '!', '.');
  std::ofstream out = createOrThrow(path);
  out << "! SIMPACK " << (type == 0 ? "rail" : "wheel") << " profile " << baseName(path) << "\n";
  out << "  header.begin\n";
  out << "    version       =  1      ! Version flag\n";
  out << "    type          =  " << type << "      ! 0=rail profile, 1=wheel profile\n";
  out << "  header.end\n";
  out << "  spline.begin\n";
  out << "    approx.smooth  = +0.000000000000000e+00   ! Approximation smoothing value\n";
  out << "    comment        = '" << safe_comment << "'\n";
  out << "    point.dist.min = +0.000000000000000e+00\n";
  out << "    shift.y        = +0.000000000000000e+00\n";
  out << "    shift.z        = +0.000000000000000e+00\n";
  out << "    rotate         = +0.000000000000000e+00\n";
  out << "    mirror.y       =  0\n";
  out << "    mirror.z       =  0\n";
  out << "    inversion      =  0\n";
  out << "    units.len.f    = +1.000000000000000e+03   ! lengths in mm\n";
  out << "    units.ang.f    = +1.000000000000000e+00   ! angles in rad\n";
  out << "    point.begin\n";
  out << "    ! y (toward the field side)  z (down)\n";
  for (const Eigen::Vector2d& p : points_yz)
    out << fileNumber(-p.x() * 1e3) << "  " << fileNumber(-p.y() * 1e3) << "\n";
  out << "    point.end\n";
  out << "  spline.end\n";
  closeOrThrow(out, path);
}

}  // namespace contact
}  // namespace rail
