// Kalker's creepage and spin coefficients c11, c22, c23, c33 (linear rolling contact theory),
// tabulated against the axis ratio of the contact ellipse and Poisson's ratio.
// Source of the numbers: Kalker 1990, "Three-Dimensional Elastic Bodies in Rolling Contact",
// Table E.3 (see data/kalker_coefficients.csv for the full citation).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace rail::contact {

/// Kalker coefficients (dimensionless) for one contact.
struct KalkerCoefficients {
  double c11 = 0.0;         ///< longitudinal creepage coefficient
  double c22 = 0.0;         ///< lateral creepage coefficient
  double c23 = 0.0;         ///< lateral creepage / spin coupling coefficient
  double c33 = 0.0;         ///< spin coefficient
  std::uint32_t flags = 0;  ///< KalkerFlag bits
};

enum KalkerFlag : std::uint32_t {
  kKalkerOk = 0u,
  kKalkerAxisRatioClamped = 1u << 0,  ///< a/b outside the table range [0.1, 10]: end value used
  kKalkerPoissonClamped = 1u << 1,    ///< nu outside [0, 0.5]: clamped
  kKalkerBadInput = 1u << 2,          ///< non-finite or non-positive a/b
};

/// Immutable table of Kalker coefficients. Interpolation: piecewise linear in the tabulated
/// axis ratio g (g = a/b for a <= b, g = b/a for a > b) and quadratic Lagrange in nu through
/// the three tabulated values nu = 0, 0.25, 0.5 (exact at every tabulated point).
class KalkerTable {
 public:
  static constexpr int kNumPoisson = 3;
  static constexpr std::array<double, kNumPoisson> kPoisson{0.0, 0.25, 0.5};

  /// One tabulated axis ratio: c[j][i] = coefficient j (0:c11 1:c22 2:c23 3:c33) at kPoisson[i].
  struct Row {
    double a_over_b = 0.0;
    std::array<std::array<double, kNumPoisson>, 4> c{};
  };

  /// Compiled-in copy of data/kalker_coefficients.csv (same source, same digits).
  static const KalkerTable& builtin();

  /// Loads a table in the CSV format of data/kalker_coefficients.csv ('#' comments, one header
  /// line, 14 columns). Throws std::runtime_error "file:line: message" on malformed input.
  static KalkerTable load(const std::string& path);

  /// Coefficients at axis ratio a/b (a rolling, b lateral) and Poisson ratio nu.
  /// Allocation-free, no exceptions; out-of-range input is clamped and flagged.
  KalkerCoefficients evaluate(double a_over_b, double nu) const noexcept;

  const std::vector<Row>& rows() const noexcept { return rows_; }

  /// Builds a table from rows (checked: >= 2 rows, strictly increasing a/b, positive c).
  /// `origin` names the source in error messages.
  static KalkerTable fromRows(std::vector<Row> rows, const std::string& origin);

 private:
  std::vector<Row> rows_;
  std::vector<double> x_;  ///< interpolation coordinate: g for a <= b, 2 - g for a > b
};

}  // namespace rail::contact
