// Benchmark (not a test): the K_eff solve of the moving window's Newmark step in each factor layout
// (sparse_cholesky.hpp), on the paper scene's window (config/scenes/paper_demo.yaml) with the coach's front
// wheel at a given arc length. Prints, per layout, the factor's size and the median time of a whole solve
// with the caches warm (the solve repeated) and with 32 MB read between solves (as in a co-simulation step, where the
// right-hand side, the contacts and the vehicle evict the factor), the layouts interleaved run by run, and
// the median time of six influence columns (solveUnitColumns). The largest difference of each layout's
// solution from the supernodal CHOLMOD solve's is printed beside.
//   bench_factor_solve [repeats] [s_front]   (defaults 500 and 275 m: the R 500 m curve)
#include <cstdio>
#include <vector>

#include <rail_core/scene_loader.hpp>

#include "rail_contact/tool_args.hpp"
#include "rail_core/testing/fixtures.hpp"
#include "rail_track_node/sparse_cholesky.hpp"
#include "rail_track_node/track_window.hpp"

namespace rt = rail::track;
using Clock = rail::tools::BenchClock;
using rail::tools::median;
using rail::tools::secondsSince;

namespace {
const char* const kUsage =
    "usage: bench_factor_solve [repeats] [s_front]\n"
    "Median K_eff solve of the paper scene's track window in each factor layout, caches warm and evicted,\n"
    "and the median of six influence columns; the median right-hand side of a Newmark step on the same window.\n"
    "Defaults 500 repeats, front wheel at 275 m (the curve).\n";

constexpr double kVehicleLength = 21.7;  // m, first to last wheelset of the paper's coach (Table 3)

std::vector<double> g_evict(4 << 20, 1.0);  // 32 MB
double evictCaches() {
  double sum = 0.0;
  for (std::size_t i = 0; i < g_evict.size(); i += 8) sum += (g_evict[i] += 1.0);
  return sum;
}

}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, 2)) return 0;
  const int repeats = static_cast<int>(rail::tools::positionalNumber(argc, argv, 1, 500, 5, kUsage));
  const double s_front = rail::tools::positionalNumber(argc, argv, 2, 275.0, kVehicleLength + 10.0, kUsage);
  const rail::core::Scene paper =
      rail::core::loadSceneFile(rail::core::fixtures::configDir() + "/scenes/paper_demo.yaml");
  rt::TrackWindowSettings settings;
  settings.vehicle_length = kVehicleLength;
  settings.track_step = paper.solver.track_step;
  const rt::TrackWindow window(rt::resolveTrackLine(paper), settings, s_front - kVehicleLength, s_front);
  const rt::LinearSystem& sys = window.model().system;
  const double h = paper.solver.track_step;
  const Eigen::SparseMatrix<double> K_eff = sys.K + (4.0 / (h * h)) * sys.M + (2.0 / h) * sys.C;
  const int n = static_cast<int>(K_eff.rows());
  std::printf("paper scene window, front wheel at %.1f m: %d DOFs, nnz(K_eff) %ld, h = %g s, %d repeats\n", s_front, n,
              static_cast<long>(K_eff.nonZeros()), h, repeats);

  const std::vector<rt::CholeskyLayout> layouts = {rt::CholeskyLayout::kSupernodal, rt::CholeskyLayout::kSimplicial,
                                                   rt::CholeskyLayout::kSimplicialTwoParts,
                                                   rt::CholeskyLayout::kBlockedTwoParts};
  std::vector<std::unique_ptr<rt::SparseCholesky>> factors;
  for (rt::CholeskyLayout layout : layouts) factors.emplace_back(new rt::SparseCholesky(K_eff, layout));
  const Eigen::VectorXd b = Eigen::VectorXd::Random(n);
  std::vector<Eigen::VectorXd> x(layouts.size(), Eigen::VectorXd::Zero(n));
  std::vector<std::vector<double>> warm(layouts.size()), evicted(layouts.size()), columns(layouts.size());
  Eigen::MatrixXd unit_x(n, rt::SparseCholesky::kMaxUnitColumns);
  int unit[rt::SparseCholesky::kMaxUnitColumns];
  for (int c = 0; c < rt::SparseCholesky::kMaxUnitColumns; ++c) unit[c] = n / 3 + c;
  double sink = 0.0;
  for (int r = 0; r < repeats; ++r)
    for (std::size_t l = 0; l < layouts.size(); ++l) {
      factors[l]->solve(b, x[l]);
      Clock::time_point t0 = Clock::now();
      factors[l]->solve(b, x[l]);
      warm[l].push_back(secondsSince(t0));
      sink += evictCaches();
      t0 = Clock::now();
      factors[l]->solve(b, x[l]);
      evicted[l].push_back(secondsSince(t0));
      t0 = Clock::now();
      factors[l]->solveUnitColumns(unit, rt::SparseCholesky::kMaxUnitColumns, unit_x);
      columns[l].push_back(secondsSince(t0));
    }
  for (std::size_t l = 0; l < layouts.size(); ++l)
    std::printf(
        "  %-28s nnz(L) %7.0f  solve %6.1f us warm, %6.1f us evicted  six columns %6.1f us  |x - x_ref| %.2g "
        "(|x| %.2g)\n",
        layouts[l] == rt::CholeskyLayout::kBlockedTwoParts && !factors[l]->solvesInBlocks()
            ? "two parts (blocks too sparse)"
            : rt::choleskyLayoutName(layouts[l]),
        factors[l]->factorNonZeros(), 1e6 * median(warm[l]), 1e6 * median(evicted[l]), 1e6 * median(columns[l]),
        (x[l] - x[0]).cwiseAbs().maxCoeff(), x[0].cwiseAbs().maxCoeff());
  // The step's right-hand side M (c0 d + c1 v + a) + C (c2 d + v) + f_g on the same window (random state).
  rt::NewmarkIntegrator integrator(sys, h, true, nullptr, 0, rt::CholeskyLayout::kBlockedTwoParts);
  rt::NewmarkState state;
  state.d = 1e-4 * Eigen::VectorXd::Random(n);
  state.v = 1e-2 * Eigen::VectorXd::Random(n);
  state.a = Eigen::VectorXd::Random(n);
  const rt::NodalLoads no_loads(1);
  std::vector<double> rhs_warm, rhs_evicted;
  for (int r = 0; r < repeats; ++r) {
    integrator.buildRhs(state, no_loads);
    Clock::time_point t0 = Clock::now();
    integrator.buildRhs(state, no_loads);
    rhs_warm.push_back(secondsSince(t0));
    sink += evictCaches();
    t0 = Clock::now();
    integrator.buildRhs(state, no_loads);
    rhs_evicted.push_back(secondsSince(t0));
  }
  std::printf("  right-hand side (M and C in 6 x 6 blocks)  %6.1f us warm, %6.1f us evicted\n", 1e6 * median(rhs_warm),
              1e6 * median(rhs_evicted));
  return sink > 0.0 ? 0 : 1;
}
