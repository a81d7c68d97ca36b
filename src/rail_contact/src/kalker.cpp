#include "rail_contact/kalker.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace rail::contact {
namespace {

/// Interpolation coordinate: x = a/b for a <= b and x = 2 - b/a for a > b, so that linear
/// interpolation in x is linear in the tabulated ratio g on each side of the circle.
double axisCoordinate(double a_over_b) noexcept { return a_over_b <= 1.0 ? a_over_b : 2.0 - 1.0 / a_over_b; }

// Kalker 1990, "Three-Dimensional Elastic Bodies in Rolling Contact", Table E.3.
// Same numbers as data/kalker_coefficients.csv: {kind a/b (0) or b/a (1), g,
//  c11(nu=0,.25,.5), c22(...), c23(...), c33(...)}.
struct BuiltinRow {
  int kind;
  double g;
  double c[12];
};
constexpr BuiltinRow kBuiltin[] = {
    {0, 0.1, {2.51, 3.31, 4.85, 2.51, 2.52, 2.53, 0.334, 0.473, 0.731, 6.42, 8.28, 11.7}},
    {0, 0.2, {2.59, 3.37, 4.81, 2.59, 2.63, 2.66, 0.483, 0.603, 0.809, 3.46, 4.27, 5.66}},
    {0, 0.3, {2.68, 3.44, 4.80, 2.68, 2.75, 2.81, 0.607, 0.715, 0.889, 2.49, 2.96, 3.72}},
    {0, 0.4, {2.78, 3.53, 4.82, 2.78, 2.88, 2.98, 0.720, 0.823, 0.977, 2.02, 2.32, 2.77}},
    {0, 0.5, {2.88, 3.62, 4.83, 2.88, 3.01, 3.14, 0.827, 0.929, 1.07, 1.74, 1.93, 2.22}},
    {0, 0.6, {2.98, 3.72, 4.91, 2.98, 3.14, 3.31, 0.930, 1.03, 1.18, 1.56, 1.68, 1.86}},
    {0, 0.7, {3.09, 3.81, 4.97, 3.09, 3.28, 3.48, 1.03, 1.14, 1.29, 1.43, 1.50, 1.60}},
    {0, 0.8, {3.19, 3.91, 5.05, 3.19, 3.41, 3.65, 1.13, 1.25, 1.40, 1.34, 1.37, 1.42}},
    {0, 0.9, {3.29, 4.01, 5.12, 3.29, 3.54, 3.82, 1.23, 1.36, 1.51, 1.27, 1.27, 1.27}},
    {0, 1.0, {3.40, 4.12, 5.20, 3.40, 3.67, 3.98, 1.33, 1.47, 1.63, 1.21, 1.19, 1.16}},
    {1, 0.9, {3.51, 4.22, 5.30, 3.51, 3.81, 4.16, 1.44, 1.59, 1.77, 1.16, 1.11, 1.06}},
    {1, 0.8, {3.65, 4.36, 5.42, 3.65, 3.99, 4.39, 1.58, 1.75, 1.94, 1.10, 1.04, 0.954}},
    {1, 0.7, {3.82, 4.54, 5.58, 3.82, 4.21, 4.67, 1.76, 1.95, 2.18, 1.05, 0.965, 0.852}},
    {1, 0.6, {4.06, 4.78, 5.80, 4.06, 4.50, 5.04, 2.01, 2.23, 2.50, 1.01, 0.892, 0.751}},
    {1, 0.5, {4.37, 5.10, 6.11, 4.37, 4.90, 5.56, 2.35, 2.62, 2.96, 0.958, 0.819, 0.650}},
    {1, 0.4, {4.84, 5.57, 6.57, 4.84, 5.48, 6.31, 2.88, 3.24, 3.70, 0.912, 0.747, 0.549}},
    {1, 0.3, {5.57, 6.34, 7.34, 5.57, 6.40, 7.51, 3.79, 4.32, 5.01, 0.868, 0.674, 0.446}},
    {1, 0.2, {6.96, 7.78, 8.82, 6.96, 8.14, 9.79, 5.72, 6.63, 7.89, 0.828, 0.601, 0.341}},
    {1, 0.1, {10.7, 11.7, 12.9, 10.7, 12.8, 16.0, 12.2, 14.6, 18.0, 0.795, 0.526, 0.228}},
};

KalkerTable::Row makeRow(bool b_over_a, double g, const double* c) {
  KalkerTable::Row r;
  r.a_over_b = b_over_a ? 1.0 / g : g;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < KalkerTable::kNumPoisson; ++i) r.c[j][i] = c[3 * j + i];
  return r;
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

[[noreturn]] void fail(const std::string& path, int line, const std::string& msg) {
  std::ostringstream os;
  os << path << ":" << line << ": " << msg;
  throw std::runtime_error(os.str());
}

double parseNumber(const std::string& field, const std::string& path, int line, const char* name) {
  const std::string t = trim(field);
  if (t.empty()) fail(path, line, std::string("empty value for ") + name);
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(t.c_str(), &end);
  if (end != t.c_str() + t.size() || errno == ERANGE || !std::isfinite(v))
    fail(path, line, std::string("not a number for ") + name + " ('" + t + "')");
  return v;
}

}  // namespace

constexpr std::array<double, KalkerTable::kNumPoisson> KalkerTable::kPoisson;

KalkerTable KalkerTable::fromRows(std::vector<Row> rows, const std::string& origin) {
  if (rows.size() < 2) throw std::runtime_error(origin + ": Kalker table needs at least 2 rows");
  KalkerTable t;
  t.x_.reserve(rows.size());
  for (std::size_t k = 0; k < rows.size(); ++k) {
    const Row& r = rows[k];
    if (!(r.a_over_b > 0.0) || !std::isfinite(r.a_over_b)) {
      std::ostringstream os;
      os << origin << ": row " << k + 1 << ": a/b must be > 0 (got " << r.a_over_b << ")";
      throw std::runtime_error(os.str());
    }
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < kNumPoisson; ++i)
        if (!(r.c[j][i] > 0.0) || !std::isfinite(r.c[j][i])) {
          std::ostringstream os;
          os << origin << ": row " << k + 1 << ": coefficient " << j << "," << i << " must be > 0 (got " << r.c[j][i]
             << ")";
          throw std::runtime_error(os.str());
        }
    const double x = axisCoordinate(r.a_over_b);
    if (!t.x_.empty() && !(x > t.x_.back())) {
      std::ostringstream os;
      os << origin << ": row " << k + 1 << ": a/b not increasing (" << r.a_over_b << " after " << rows[k - 1].a_over_b
         << ")";
      throw std::runtime_error(os.str());
    }
    t.x_.push_back(x);
  }
  t.rows_ = std::move(rows);
  return t;
}

const KalkerTable& KalkerTable::builtin() {
  static const KalkerTable table = [] {
    std::vector<Row> rows;
    for (const auto& b : kBuiltin) rows.push_back(makeRow(b.kind == 1, b.g, b.c));
    return fromRows(std::move(rows), "builtin Kalker table");
  }();
  return table;
}

KalkerTable KalkerTable::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open Kalker coefficient file");
  std::vector<Row> rows;
  std::string line;
  int line_no = 0;
  bool header_seen = false;
  while (std::getline(in, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (t.empty() || t[0] == '#') continue;
    if (!header_seen) {
      header_seen = true;
      if (t.rfind("kind", 0) != 0) fail(path, line_no, "expected header line starting with 'kind'");
      continue;
    }
    std::vector<std::string> f;
    std::stringstream ss(t);
    std::string cell;
    while (std::getline(ss, cell, ',')) f.push_back(cell);
    if (f.size() != 14) {
      std::ostringstream os;
      os << "expected 14 comma-separated fields, got " << f.size();
      fail(path, line_no, os.str());
    }
    const std::string kind = trim(f[0]);
    if (kind != "a/b" && kind != "b/a") fail(path, line_no, "kind must be 'a/b' or 'b/a' (got '" + kind + "')");
    const double g = parseNumber(f[1], path, line_no, "g");
    if (!(g > 0.0 && g <= 1.0)) {
      std::ostringstream os;
      os << "g must be in (0, 1] (got " << g << ")";
      fail(path, line_no, os.str());
    }
    double c[12];
    static const char* names[12] = {"c11_nu0", "c11_nu025", "c11_nu05", "c22_nu0", "c22_nu025", "c22_nu05",
                                    "c23_nu0", "c23_nu025", "c23_nu05", "c33_nu0", "c33_nu025", "c33_nu05"};
    for (int k = 0; k < 12; ++k) {
      c[k] = parseNumber(f[2 + k], path, line_no, names[k]);
      if (!(c[k] > 0.0)) {
        std::ostringstream os;
        os << names[k] << " must be > 0 (got " << c[k] << ")";
        fail(path, line_no, os.str());
      }
    }
    Row r = makeRow(kind == "b/a", g, c);
    if (!rows.empty() && !(axisCoordinate(r.a_over_b) > axisCoordinate(rows.back().a_over_b))) {
      std::ostringstream os;
      os << "a/b not increasing (" << r.a_over_b << " after " << rows.back().a_over_b << ")";
      fail(path, line_no, os.str());
    }
    rows.push_back(r);
  }
  if (!header_seen) fail(path, line_no, "no header line found");
  if (rows.size() < 2) fail(path, line_no, "Kalker table needs at least 2 data rows");
  return fromRows(std::move(rows), path);
}

KalkerCoefficients KalkerTable::evaluate(double a_over_b, double nu) const noexcept {
  KalkerCoefficients out;
  std::uint32_t flags = kKalkerOk;
  if (!(a_over_b > 0.0) || !std::isfinite(a_over_b)) {
    flags |= kKalkerBadInput;
    a_over_b = 1.0;
  }
  if (!(nu >= 0.0)) {  // also catches NaN
    flags |= kKalkerPoissonClamped;
    nu = 0.0;
  } else if (nu > 0.5) {
    flags |= kKalkerPoissonClamped;
    nu = 0.5;
  }
  double x = axisCoordinate(a_over_b);
  if (x < x_.front()) {
    x = x_.front();
    flags |= kKalkerAxisRatioClamped;
  } else if (x > x_.back()) {
    x = x_.back();
    flags |= kKalkerAxisRatioClamped;
  }
  // Segment [x_[i], x_[i+1]] containing x.
  std::size_t i = static_cast<std::size_t>(std::upper_bound(x_.begin(), x_.end(), x) - x_.begin());
  i = i == 0 ? 0 : i - 1;
  if (i + 1 >= x_.size()) i = x_.size() - 2;
  const double t = (x - x_[i]) / (x_[i + 1] - x_[i]);
  // Quadratic Lagrange weights through nu = 0, 0.25, 0.5.
  const double w0 = (nu - 0.25) * (nu - 0.5) / ((0.0 - 0.25) * (0.0 - 0.5));
  const double w1 = (nu - 0.0) * (nu - 0.5) / ((0.25 - 0.0) * (0.25 - 0.5));
  const double w2 = (nu - 0.0) * (nu - 0.25) / ((0.5 - 0.0) * (0.5 - 0.25));
  double c[4];
  for (int j = 0; j < 4; ++j) {
    const auto& lo = rows_[i].c[j];
    const auto& hi = rows_[i + 1].c[j];
    // t == 1 only at the last node: take it verbatim so tabulated values are hit exactly.
    const double v0 = t < 1.0 ? lo[0] + t * (hi[0] - lo[0]) : hi[0];
    const double v1 = t < 1.0 ? lo[1] + t * (hi[1] - lo[1]) : hi[1];
    const double v2 = t < 1.0 ? lo[2] + t * (hi[2] - lo[2]) : hi[2];
    c[j] = w0 * v0 + w1 * v1 + w2 * v2;
  }
  out.c11 = c[0];
  out.c22 = c[1];
  out.c23 = c[2];
  out.c33 = c[3];
  out.flags = flags;
  return out;
}

}  // namespace rail::contact
