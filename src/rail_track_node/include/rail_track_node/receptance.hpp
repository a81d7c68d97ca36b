// Point receptance of the FE track (frequency response x/F at the point and in the direction of a unit
// harmonic force): (K - omega^2 M + i omega C) x = f, solved with a complex sparse LU. For analysis tools,
// not for the time loop.
#pragma once

#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <Eigen/SparseLU>

#include <complex>
#include <memory>
#include <vector>

#include "rail_track_node/elements.hpp"
#include "rail_track_node/track_model.hpp"

namespace rail {
namespace track {

/// Where and how a unit force excites the rail: on rail `rail` (RailSide) at arc length s, at the top of
/// the rail head, vertical (downward along the track normal) or lateral (toward the field side).
struct ReceptancePoint {
  enum class Direction { kVertical, kLateral };
  int rail = 0;
  double arc_length = 0.0;  ///< s of the point, m
  Direction direction = Direction::kVertical;
};

/// Solver of the point receptances of a set of points over frequencies.
class ReceptanceSolver {
 public:
  /// model must outlive the solver. head_arm: rail centroid to head top (m). Builds the unit load
  /// vectors (throws std::runtime_error if a point is off the rails) and analyses the sparsity pattern.
  ReceptanceSolver(const TrackModel& model, double head_arm, const std::vector<ReceptancePoint>& points);

  /// Point receptances (m/N, complex: displacement in the force's direction over the force) of every
  /// point at frequency f_hz (> 0). Factorises K - omega^2 M + i omega C once for all points.
  void solve(double f_hz, std::vector<std::complex<double>>& receptance);

 private:
  using SparseC = Eigen::SparseMatrix<std::complex<double>>;
  const TrackModel& model_;
  SparseC K_, M_, C_, A_;
  std::vector<Eigen::VectorXcd> f_;
  Eigen::SparseLU<SparseC> lu_;
};

/// n frequencies from f_lo to f_hi (Hz) evenly spaced on a logarithmic axis.
std::vector<double> logSpacedFrequencies(double f_lo, double f_hi, int n);

/// Frequency of the largest value of y(f) for f in [f_lo, f_hi], refined by a parabola through the
/// largest sample and its neighbours (in log f). Returns 0 if no sample lies in the band.
double peakFrequency(const std::vector<double>& f, const std::vector<double>& y, double f_lo, double f_hi);

/// Pinned-pinned frequency of an Euler-Bernoulli rail on supports d apart (m):
/// f_pp = (pi / (2 d^2)) sqrt(E I_y / (rho A)) (Hz), the first bending mode of a span with nodes at the
/// supports (vertical bending, I_y).
double pinnedPinnedFrequency(const BeamSection& rail, double d);

}  // namespace track
}  // namespace rail
