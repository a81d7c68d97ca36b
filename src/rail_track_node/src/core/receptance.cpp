// Point receptance of the FE track (see receptance.hpp).
#include "rail_track_node/receptance.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "rail_track_node/newmark.hpp"
#include "rail_track_node/track_simulator.hpp"

namespace rail {
namespace track {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

ReceptanceSolver::ReceptanceSolver(const TrackModel& model, double head_arm, const std::vector<ReceptancePoint>& points)
    : model_(model) {
  const LinearSystem& sys = model.system;
  K_ = sys.K.cast<std::complex<double>>();
  M_ = sys.M.cast<std::complex<double>>();
  C_ = sys.C.cast<std::complex<double>>();
  // The sum keeps the union of the three patterns (explicit zeros included), the same at every frequency.
  A_ = K_ + M_ + C_;
  A_.makeCompressed();
  lu_.analyzePattern(A_);
  NodalLoads loads(64);
  for (const ReceptancePoint& p : points) {
    loads.clear();
    const bool vertical = p.direction == ReceptancePoint::Direction::kVertical;
    if (!addRailHeadLoad(model.mesh, model.data.layout.rail_inclination, head_arm, p.rail, p.arc_length,
                         vertical ? 1.0 : 0.0, vertical ? 0.0 : 1.0, loads)) {
      std::ostringstream os;
      os << "receptance point at s = " << p.arc_length << " m is not on the meshed rails";
      throw std::runtime_error(os.str());
    }
    Eigen::VectorXcd f = Eigen::VectorXcd::Zero(sys.size());
    for (int k = 0; k < loads.size(); ++k) f(loads.index(k)) += loads.value(k);
    f_.push_back(f);
  }
}

void ReceptanceSolver::solve(double f_hz, std::vector<std::complex<double>>& receptance) {
  const double w = 2.0 * kPi * f_hz;
  const std::complex<double> iw(0.0, w);
  A_ = K_ - (w * w) * M_ + iw * C_;
  lu_.factorize(A_);
  if (lu_.info() != Eigen::Success) {
    std::ostringstream os;
    os << "receptance: the dynamic stiffness at " << f_hz << " Hz is singular";
    throw std::runtime_error(os.str());
  }
  receptance.resize(f_.size());
  for (std::size_t k = 0; k < f_.size(); ++k) {
    const Eigen::VectorXcd x = lu_.solve(f_[k]);
    // Work-conjugate response: the generalised unit load vector projects x onto the loaded point and
    // direction (reciprocity of N^T), giving the displacement along the force there.
    receptance[k] = f_[k].transpose() * x;
  }
}

std::vector<double> logSpacedFrequencies(double f_lo, double f_hi, int n) {
  std::vector<double> f(n);
  for (int k = 0; k < n; ++k) f[k] = f_lo * std::pow(f_hi / f_lo, n > 1 ? static_cast<double>(k) / (n - 1) : 0.0);
  return f;
}

double peakFrequency(const std::vector<double>& f, const std::vector<double>& y, double f_lo, double f_hi) {
  int best = -1;
  for (std::size_t k = 0; k < f.size(); ++k)
    if (f[k] >= f_lo && f[k] <= f_hi && (best < 0 || y[k] > y[best])) best = static_cast<int>(k);
  if (best < 0) return 0.0;
  if (best == 0 || best + 1 >= static_cast<int>(f.size())) return f[best];
  // Parabola through three points in x = log f.
  const double x0 = std::log(f[best - 1]), x1 = std::log(f[best]), x2 = std::log(f[best + 1]);
  const double y0 = y[best - 1], y1 = y[best], y2 = y[best + 1];
  const double d01 = (y1 - y0) / (x1 - x0), d12 = (y2 - y1) / (x2 - x1);
  const double c = (d12 - d01) / (x2 - x0);
  if (!(c < 0.0)) return f[best];
  const double x_peak = 0.5 * (x0 + x1) - d01 / (2.0 * c);
  return std::exp(std::min(std::max(x_peak, x0), x2));
}

double pinnedPinnedFrequency(const BeamSection& rail, double d) {
  return kPi / (2.0 * d * d) * std::sqrt(rail.E * rail.I_y / (rail.rho * rail.A));
}

}  // namespace track
}  // namespace rail
