// The track step's fast path against its reference path: the next step's right-hand side and solve on a
// second thread (solve_beside) with the simplicial factor and its own triangular solves, against the solve
// inside the step on CHOLMOD's supernodal factor (the path of the earlier releases). 8 rigid wheels of the
// paper's coach roll at 30 m/s on a moving track window through a transition into a canted curve and are
// pushed toward the outer rail until their flanges touch; the window moves and refactorises on the way.
// The wheel forces agree within 1e-6 of the static wheel load at every step and the rail displacements
// within 1e-9 of their largest value. Why that tolerance: the two paths differ in rounding only, and the
// contact forces are solved by Newton to contact points within 1e-12 m; at the contact's stiffness
// (about 1e9 N/m per contact) that leaves up to ~1e-3 N between two paths, 1e-8 of the wheel load, and the
// linear track carries such differences without growing them. A change of the physics (a lost load, a
// stale base solve after a window move) differs by orders of magnitude more. The step split in two
// (stepForces, then finishStep, as the run loop calls it) gives the one-call step's figures exactly.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <rail_contact/profile.hpp>
#include <rail_core/testing/fixtures.hpp>

#include "rail_track_node/cosim_track.hpp"
#include "rail_track_node/sparse_cholesky.hpp"

namespace rt = rail::track;
namespace rc = rail::contact;
namespace cc = rail::core::coupling;
using rail::core::Scene;

namespace {

// The paper's data on a 100 m line: 20 m straight, a 40 m transition to R = 500 m left with 160 mm cant,
// 40 m of the curve; a window 5 m beyond the end wheels, moved 0.6 m (one bay) at a time.
Scene curveScene() {
  const std::string text =
      "name: p\ntrack:\n  gauge: 1.668\n  cant_reference_width: 1.733\n  data: ../track/paper_track.yaml\n"
      "  segments:\n"
      "    - {type: straight, length: 20.0}\n"
      "    - {type: transition, length: 40.0, direction: left, radius_start: 0, radius_end: 500.0,"
      " cant_start: 0.0, cant_end: 0.160}\n"
      "    - {type: circular, length: 40.0, direction: left, radius: 500.0, cant: 0.160}\n"
      "vehicle:\n  data: ../vehicle/paper_coach.yaml\n  start_arc_length: 55.0\n  speed: 30.0\n"
      "  back_to_back: 1.592\n  nominal_radius: 0.445\n  wheelsets: 4\n"
      "effects:\n  track_model: flexible\n"
      "solver:\n  track_step: 2e-5\n  vehicle_max_step: 2e-5\n  end: {time: 1.0}\n"
      "  track_window: {enabled: true, behind: 5.0, ahead: 5.0, shift: 0.6}\n";
  return rail::core::fixtures::sceneFromText(text, "p.yaml");
}

constexpr double kOffsets[4] = {0.0, 2.7, 19.0, 21.7};  // behind the leading wheelset, m (paper coach)
constexpr double kQ = 72900.0;                          // the coach's static wheel load, N (order of)

// Wheelset w at s_front - kOffsets[w] on the design track, lowered by 0.7 mm over the first 10 ms, shifted
// toward the outer (right) rail by up to 7 mm over the run, yawed a little, rolling at V.
void fillFrame(const rc::TrackGeometry& geo, double s_front, double V, long k, long steps, double h,
               cc::WheelStateFrame& f) {
  const double r0 = 0.445, t = k * h;
  const double taping_y = 0.5 * 1.592 + rc::flangeBackY(rc::makeS1002());
  const double z = r0 - 0.7e-3 * std::min(1.0, t / 0.01);
  const double y = -7e-3 * std::min(1.0, static_cast<double>(k) / (0.6 * static_cast<double>(steps)));
  f.count = 8;
  f.step = static_cast<std::uint64_t>(k);
  f.time = t;
  rc::TrackPoint tp;
  for (int ws = 0; ws < 4; ++ws) {
    const double s = s_front - kOffsets[ws];
    geo.centre(s, tp);
    const Eigen::Matrix3d R =
        tp.R_track_to_world * Eigen::AngleAxisd(2e-3 * (ws - 1.5), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d v = V * tp.R_track_to_world.col(0);
    const Eigen::Vector3d omega = R.col(1) * (V / r0) + tp.R_track_to_world.col(2) * (V * tp.curvature);
    for (int side = 0; side < 2; ++side) {
      cc::WheelState& w = f.wheels[static_cast<std::size_t>(2 * ws + side)];
      w.id = static_cast<std::uint32_t>(2 * ws + side);
      const Eigen::Vector3d arm = R * Eigen::Vector3d(0.0, side == 0 ? taping_y : -taping_y, 0.0);
      w.p_wheel_in_world = tp.p_center_in_world + tp.R_track_to_world * Eigen::Vector3d(0.0, y, z) + arm;
      w.arc_length = s;
      w.R_wheelset_to_world = R;
      w.v_wheel_in_world = v + omega.cross(arm);
      w.omega_wheelset_in_world = omega;
    }
  }
}

struct PathRun {
  std::vector<double> force;       // per step and wheel: x, y, z of the wheel-centre force, N
  std::vector<double> deflection;  // per step: left and right rail at the section, x, y, z, m
  std::vector<double> gaps;        // every 50th step (exact gaps asked for): each contact slot's penetration, m
  int moves = 0, rebuilds = 0, flange_steps = 0, refused = 0;
  long long skipped = 0;  // searches skipped by far wheel surfaces
  long first_rows = 0;    // steps whose Newton started on the base solve's first rows
};

// split: each step as stepForces and finishStep (the run loop's order: the wrenches before the rest).
// skip: CosimTrackOptions::skip_far_searches.
PathRun runPath(bool beside, rt::CholeskyLayout layout, long steps, bool split = false, bool skip = true) {
  const Scene sc = curveScene();
  rt::CosimTrackOptions o;
  o.window.vehicle_length = 21.7;
  o.solve_beside = beside;
  o.factor_layout = layout;
  o.skip_far_searches = skip;
  rt::CosimTrack track(rt::resolveCosimTrack(sc), o);
  const int section = track.addSection(50.0);
  const double V = 30.0, h = sc.solver.track_step;
  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  rt::RailSectionDeflection def;
  PathRun r;
  for (long k = 0; k < steps; ++k) {
    fillFrame(track.geometry(), 55.0 + V * k * h, V, k, steps, h, frame);
    const bool exact_gaps = k % 50 == 0;  // as the run loop does at its output steps
    track.setExactGaps(exact_gaps);
    if ((split ? track.stepForces(frame, out) : track.step(frame, out)) != rt::CosimStepStatus::kOk) {
      ++r.refused;
      continue;
    }
    bool flange = false;
    for (int i = 0; i < 8; ++i) {
      for (int j = 0; j < 3; ++j) r.force.push_back(out.wheels[static_cast<std::size_t>(i)].f_wheel_in_world(j));
      for (const rc::ContactPointResult& cp : track.contact(i).contact)
        flange = flange || (cp.active && cp.N > 0.0 && cp.surface == rc::kFlange);
    }
    r.flange_steps += flange ? 1 : 0;
    for (int i = 0; i < 8 && exact_gaps; ++i)
      for (const rc::ContactPointResult& cp : track.contact(i).contact) r.gaps.push_back(cp.penetration);
    if (split) track.finishStep();
    track.sectionDeflection(section, def);
    for (int j = 0; j < 3; ++j) {
      r.deflection.push_back(def.displacement[0](j));
      r.deflection.push_back(def.displacement[1](j));
    }
  }
  r.moves = track.windowMoves();
  r.first_rows = track.firstRowsSteps();
  r.rebuilds = track.windowRebuilds();
  for (int i = 0; i < 8; ++i)
    for (const rc::DetectionWork& d : track.contactWork(i).detection) r.skipped += d.skipped;
  return r;
}

double largestDifference(const std::vector<double>& a, const std::vector<double>& b) {
  double d = 0.0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) d = std::max(d, std::abs(a[i] - b[i]));
  return a.size() == b.size() ? d : HUGE_VAL;
}

// The curve scene's first track window, its solve inside the step.
std::unique_ptr<rt::CosimTrack> curveWindowTrack(const Scene& scene = curveScene()) {
  rt::CosimTrackOptions o;
  o.window.vehicle_length = 21.7;
  o.solve_beside = false;
  return std::make_unique<rt::CosimTrack>(rt::resolveCosimTrack(scene), o);
}

// curveScene with its coach on the straight instead (the window's rails and sleepers square to one line).
Scene straightScene() {
  const std::string text =
      "name: p\ntrack:\n  gauge: 1.668\n  cant_reference_width: 1.733\n  data: ../track/paper_track.yaml\n"
      "  segments:\n    - {type: straight, length: 100.0}\n"
      "vehicle:\n  data: ../vehicle/paper_coach.yaml\n  start_arc_length: 55.0\n  speed: 30.0\n"
      "  back_to_back: 1.592\n  nominal_radius: 0.445\n  wheelsets: 4\n"
      "effects:\n  track_model: flexible\n"
      "solver:\n  track_step: 2e-5\n  vehicle_max_step: 2e-5\n  end: {time: 1.0}\n"
      "  track_window: {enabled: true, behind: 5.0, ahead: 5.0, shift: 0.6}\n";
  return rail::core::fixtures::sceneFromText(text, "p.yaml");
}

// K_eff = K + 4/h^2 M + 2/h C of the track's window at h = 2e-5 s.
Eigen::SparseMatrix<double> effectiveStiffness(const rt::CosimTrack& track) {
  const rt::LinearSystem& sys = track.trackWindow()->model().system;
  return sys.K + (4.0 / 4e-10) * sys.M + (2.0 / 2e-5) * sys.C;
}

// factor's solve of b in its three phases, the parts of each pass on two threads at once.
void solveInPhasesOnTwoThreads(rt::SparseCholesky& factor, const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  std::thread other([&] { factor.forwardPart(1, b); });
  factor.forwardPart(0, b);
  other.join();
  factor.solveSeparator(b, x);
  std::thread other_back([&] { factor.backwardPart(1, x); });
  factor.backwardPart(0, x);
  other_back.join();
}

double largestMagnitude(const std::vector<double>& a) {
  double m = 0.0;
  for (double x : a) m = std::max(m, std::abs(x));
  return m;
}

}  // namespace

TEST(CosimTrackPaths, TheFastPathGivesTheReferencePathsForcesAndRails) {
  const long steps = 2500;  // 50 ms, 1.5 m: two window moves
  const PathRun ref = runPath(false, rt::CholeskyLayout::kSupernodal, steps);
  const PathRun fast = runPath(true, rt::CholeskyLayout::kSimplicial, steps);
  const PathRun serial = runPath(false, rt::CholeskyLayout::kSimplicial, steps);
  const PathRun split = runPath(true, rt::CholeskyLayout::kSimplicial, steps, true);
  ASSERT_EQ(ref.refused, 0);
  ASSERT_EQ(fast.refused, 0);
  EXPECT_GE(ref.moves, 2);
  EXPECT_GE(ref.rebuilds, 1) << "a move onto new matrices (the curve) must be part of the run";
  EXPECT_GT(ref.flange_steps, steps / 10) << "the run must include flange contact";
  EXPECT_EQ(fast.moves, ref.moves);
  EXPECT_EQ(fast.flange_steps, ref.flange_steps);
  const double df = largestDifference(fast.force, ref.force), ds = largestDifference(serial.force, ref.force);
  const double dd = largestDifference(fast.deflection, ref.deflection), peak = largestMagnitude(ref.deflection);
  EXPECT_LT(df, 1e-6 * kQ);
  EXPECT_LT(ds, 1e-6 * kQ);
  EXPECT_LT(dd, 1e-9 * peak);
  // The step in two parts does the same arithmetic in the same order as in one.
  EXPECT_EQ(largestDifference(split.force, fast.force), 0.0);
  EXPECT_EQ(largestDifference(split.deflection, fast.deflection), 0.0);
  // The factor in two parts, its solve shared by both threads: the reference's figures as the simplicial
  // path's, and exactly those of the same factor solved whole inside the step (the same operations).
  const PathRun two = runPath(true, rt::CholeskyLayout::kSimplicialTwoParts, steps);
  const PathRun two_whole = runPath(false, rt::CholeskyLayout::kSimplicialTwoParts, steps);
  ASSERT_EQ(two.refused, 0);
  EXPECT_EQ(two.flange_steps, ref.flange_steps);
  EXPECT_LT(largestDifference(two.force, ref.force), 1e-6 * kQ);
  EXPECT_LT(largestDifference(two.deflection, ref.deflection), 1e-9 * peak);
  EXPECT_EQ(largestDifference(two.force, two_whole.force), 0.0);
  EXPECT_EQ(largestDifference(two.deflection, two_whole.deflection), 0.0);
  // The same ordering's supernodal factor in blocks (the default): the same, to rounding, as the others.
  const PathRun blocked = runPath(true, rt::CholeskyLayout::kBlockedTwoParts, steps);
  const PathRun blocked_whole = runPath(false, rt::CholeskyLayout::kBlockedTwoParts, steps);
  ASSERT_EQ(blocked.refused, 0);
  EXPECT_EQ(blocked.moves, ref.moves);
  EXPECT_EQ(blocked.flange_steps, ref.flange_steps);
  const double db = largestDifference(blocked.force, ref.force);
  const double db_rail = largestDifference(blocked.deflection, ref.deflection);
  EXPECT_LT(db, 1e-6 * kQ);
  EXPECT_LT(db_rail, 1e-9 * peak);
  EXPECT_EQ(largestDifference(blocked.force, blocked_whole.force), 0.0);
  EXPECT_EQ(largestDifference(blocked.deflection, blocked_whole.deflection), 0.0);
  // ... with the Newton started on the first rows of the backward pass (not after a move, when a wheel
  // reaches a node beyond the marked ones, or when the worker was held up for 0.4 ms: so not at every step
  // on a loaded machine), never with the solve inside the step.
  EXPECT_GT(blocked.first_rows, 0);
  EXPECT_GT(two.first_rows, 0);
  EXPECT_EQ(blocked_whole.first_rows, 0);
  // Far wheel surfaces skip their searches (the default): the same forces, rails and published gaps to the
  // last bit as every surface searched at every step.
  const PathRun searched = runPath(true, rt::CholeskyLayout::kBlockedTwoParts, steps, false, false);
  EXPECT_EQ(searched.skipped, 0);
  EXPECT_GT(blocked.skipped, steps) << "the far flanges must skip searches";
  EXPECT_EQ(largestDifference(blocked.force, searched.force), 0.0);
  EXPECT_EQ(largestDifference(blocked.deflection, searched.deflection), 0.0);
  EXPECT_EQ(largestDifference(blocked.gaps, searched.gaps), 0.0);
  std::printf(
      "[ figures  ] blocked factor: forces differ by %.3g N, rail displacement by %.3g m; %lld searches "
      "skipped; %ld steps of %ld started the Newton on the first rows\n",
      db, db_rail, blocked.skipped, blocked.first_rows, steps);
  std::printf(
      "[ figures  ] %ld steps, %d moves (%d rebuilt), %d steps with flange contact, largest wheel force "
      "%.0f N: forces differ by %.3g N (fast) and %.3g N (simplicial in the step), rail displacement by "
      "%.3g m of %.3g m\n",
      steps, ref.moves, ref.rebuilds, ref.flange_steps, largestMagnitude(ref.force), df, ds, dd, peak);
}

// The simplicial factor's solves against CHOLMOD's supernodal solve on a track's K_eff; the influence
// columns of a rail node in one pass against one solve each.
TEST(SparseCholeskySolves, SimplicialMatchesSupernodalAndUnitColumnsMatchSingleSolves) {
  const std::unique_ptr<rt::CosimTrack> track = curveWindowTrack();
  const Eigen::SparseMatrix<double> K_eff = effectiveStiffness(*track);
  rt::SparseCholesky simplicial(K_eff, rt::CholeskyLayout::kSimplicial);
  rt::SparseCholesky supernodal(K_eff, rt::CholeskyLayout::kSupernodal);
  rt::SparseCholesky blocked(K_eff, rt::CholeskyLayout::kBlockedTwoParts);
  EXPECT_EQ(simplicial.layout(), rt::CholeskyLayout::kSimplicial);
  EXPECT_FALSE(blocked.isSupernodal());
  EXPECT_FALSE(simplicial.isSupernodal());
  EXPECT_TRUE(supernodal.isSupernodal());
  const int n = K_eff.rows();
  const Eigen::VectorXd b = Eigen::VectorXd::Random(n) * 1e5;
  Eigen::VectorXd x1(n), x2(n);
  simplicial.solve(b, x1);
  supernodal.solve(b, x2);
  // Both solve a system of condition ~1e8 to rounding: residuals at 1e-12 of |b|, solutions within 1e-9.
  EXPECT_LT((K_eff.selfadjointView<Eigen::Upper>() * x1 - b).norm(), 1e-12 * b.norm() * 1e3);
  EXPECT_LT((x1 - x2).norm(), 1e-9 * x2.norm());
  // Aliased: x may be b.
  Eigen::VectorXd x3 = b;
  simplicial.solve(x3, x3);
  EXPECT_EQ((x3 - x1).cwiseAbs().maxCoeff(), 0.0);
  // The blocks (inverted diagonal blocks: their own rounding) solve the same system as closely.
  Eigen::VectorXd x4(n), x5 = b;
  blocked.solve(b, x4);
  EXPECT_LT((K_eff.selfadjointView<Eigen::Upper>() * x4 - b).norm(), 1e-12 * b.norm() * 1e3);
  EXPECT_LT((x4 - x2).norm(), 1e-9 * x2.norm());
  blocked.solve(x5, x5);
  EXPECT_EQ((x5 - x4).cwiseAbs().maxCoeff(), 0.0);

  const rt::TrackMesh& mesh = track->trackWindow()->mesh();
  const int node = mesh.rail_nodes[1][mesh.rail_nodes[1].size() / 3];
  int dofs[6];
  for (int j = 0; j < 6; ++j) dofs[j] = mesh.dofIndex(node, j);
  Eigen::MatrixXd many(n, 6), one(n, 1), ref(n, 6), blocked_many(n, 6), blocked_one(n, 1);
  simplicial.solveUnitColumns(dofs, 6, many);
  supernodal.solveUnitColumns(dofs, 6, ref);
  blocked.solveUnitColumns(dofs, 6, blocked_many);
  for (int c = 0; c < 6; ++c) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(n), x(n), x_blocked(n);
    e(dofs[c]) = 1.0;
    simplicial.solve(e, x);
    simplicial.solveUnitColumns(dofs + c, 1, one);
    EXPECT_LT((many.col(c) - x).cwiseAbs().maxCoeff(), 1e-13 * x.cwiseAbs().maxCoeff()) << "column " << c;
    EXPECT_LT((one.col(0) - x).cwiseAbs().maxCoeff(), 1e-13 * x.cwiseAbs().maxCoeff()) << "column " << c;
    EXPECT_LT((ref.col(c) - x).cwiseAbs().maxCoeff(), 1e-9 * x.cwiseAbs().maxCoeff()) << "column " << c;
    // The blocks' columns (their forward pass skips the blocks off the unit row's path) against the blocks'
    // own solve, and against the simplicial factor's.
    blocked.solve(e, x_blocked);
    blocked.solveUnitColumns(dofs + c, 1, blocked_one);
    EXPECT_LT((blocked_many.col(c) - x_blocked).cwiseAbs().maxCoeff(), 1e-13 * x.cwiseAbs().maxCoeff()) << c;
    EXPECT_LT((blocked_one.col(0) - x_blocked).cwiseAbs().maxCoeff(), 1e-13 * x.cwiseAbs().maxCoeff()) << c;
    EXPECT_LT((x_blocked - x).cwiseAbs().maxCoeff(), 1e-9 * x.cwiseAbs().maxCoeff()) << "column " << c;
  }
  // The second column workspace: two threads solving columns at once, each in its lane, beside a solve
  // on a third, give each lane's columns exactly as one thread does (the co-simulation's worker takes
  // rail nodes in lane 1 while the loop's thread takes others in lane 0).
  for (rt::SparseCholesky* factor : {&simplicial, &blocked}) {
    Eigen::MatrixXd lane0(n, 6), lane1(n, 6), alone(n, 6);
    int other[6];
    for (int j = 0; j < 6; ++j) other[j] = mesh.dofIndex(mesh.rail_nodes[0][mesh.rail_nodes[0].size() / 2], j);
    factor->solveUnitColumns(other, 6, alone);
    Eigen::VectorXd x_beside(n);
    for (int repeat = 0; repeat < 5; ++repeat) {
      std::thread second([&] { factor->solveUnitColumns(other, 6, lane1, 1); });
      std::thread third([&] { factor->solve(b, x_beside); });
      factor->solveUnitColumns(dofs, 6, lane0, 0);
      second.join();
      third.join();
      ASSERT_EQ((lane0 - (factor == &blocked ? blocked_many : many)).cwiseAbs().maxCoeff(), 0.0) << repeat;
      ASSERT_EQ((lane1 - alone).cwiseAbs().maxCoeff(), 0.0) << repeat;
      ASSERT_EQ((x_beside - (factor == &blocked ? x4 : x1)).cwiseAbs().maxCoeff(), 0.0) << repeat;
    }
  }
}

// The factor in two parts: parts independent in L, a separator of one plane of the track, about the fill of
// CHOLMOD's own ordering, and the solve in phases on two threads equal to the whole solve.
// Both layouts in two parts (the simplicial one and the blocks).
class TwoPartsLayout : public ::testing::TestWithParam<rt::CholeskyLayout> {};

TEST_P(TwoPartsLayout, SolvedOnTwoThreadsEqualsTheWholeSolve) {
  const std::unique_ptr<rt::CosimTrack> track = curveWindowTrack();
  const Eigen::SparseMatrix<double> K_eff = effectiveStiffness(*track);
  rt::SparseCholesky whole(K_eff, rt::CholeskyLayout::kSimplicial);
  rt::SparseCholesky two(K_eff, GetParam());
  rt::SparseCholesky supernodal(K_eff, rt::CholeskyLayout::kSupernodal);
  const int n = K_eff.rows();
  EXPECT_EQ(two.layout(), GetParam());
  EXPECT_EQ(two.partRows(0) + two.partRows(1) + two.separatorRows(), n);
  EXPECT_EQ(two.partRows(0), n / 2);
  // One cross-section of the track: each rail's node where the halves meet (6 DOFs each), and at most a
  // sleeper's nodes with their pads.
  EXPECT_GT(two.separatorRows(), 0);
  EXPECT_LE(two.separatorRows(), 60);
  EXPECT_EQ(whole.partRows(0) + whole.separatorRows(), 0);
  // Fill within a quarter of CHOLMOD's unconstrained ordering's.
  EXPECT_LT(two.factorNonZeros(), 1.25 * whole.factorNonZeros());
  std::printf("[ figures  ] %d DOFs: parts %d and %d, separator %d; nnz(L) %.0f against %.0f\n", n, two.partRows(0),
              two.partRows(1), two.separatorRows(), two.factorNonZeros(), whole.factorNonZeros());

  const Eigen::VectorXd b = Eigen::VectorXd::Random(n) * 1e5;
  Eigen::VectorXd x_whole(n), x_ref(n), x_parts = Eigen::VectorXd::Zero(n);
  two.solve(b, x_whole);
  supernodal.solve(b, x_ref);
  EXPECT_LT((x_whole - x_ref).norm(), 1e-9 * x_ref.norm());
  for (int repeat = 0; repeat < 20; ++repeat) {
    solveInPhasesOnTwoThreads(two, b, x_parts);
    ASSERT_EQ((x_parts - x_whole).cwiseAbs().maxCoeff(), 0.0) << "repeat " << repeat;
  }
}

// The backward pass in two sweeps (markFirstRows): the first gives x at the marked rows of A, and the
// second the rest, together the whole solve to the last bit; on the curve's window (blocks) and on the
// straight's (simplicial loops). The marked rows are two wheels' worth: a rail node a quarter along the
// left rail and one three quarters along the right, each with its neighbours.
TEST_P(TwoPartsLayout, FirstRowsOfTheBackwardPassGiveTheirSolutionFirst) {
  const std::unique_ptr<rt::CosimTrack> curve = curveWindowTrack();
  const std::unique_ptr<rt::CosimTrack> straight = curveWindowTrack(straightScene());
  for (const rt::CosimTrack* track : {curve.get(), straight.get()}) {
    const Eigen::SparseMatrix<double> K_eff = effectiveStiffness(*track);
    rt::SparseCholesky two(K_eff, GetParam());
    const int n = K_eff.rows();
    const rt::TrackMesh& mesh = track->trackWindow()->mesh();
    std::vector<int> dofs;
    for (int r = 0; r < 2; ++r) {
      const int k = static_cast<int>(mesh.rail_nodes[r].size()) * (r == 0 ? 1 : 3) / 4;
      for (int node = k - 1; node <= k + 2; ++node)
        for (int j = 0; j < 6; ++j) {
          const int g = mesh.dofIndex(mesh.rail_nodes[r][static_cast<std::size_t>(node)], j);
          if (g >= 0) dofs.push_back(g);
        }
    }
    two.markFirstRows(dofs.data(), static_cast<int>(dofs.size()));
    int covered = 0;
    for (int i = 0; i < n; ++i) covered += two.firstCovers(i);
    for (const int g : dofs) EXPECT_TRUE(two.firstCovers(g)) << "DOF " << g;
    // The wheels' rows and their ancestors: a minor share of the rows, else the first sweep would gain nothing.
    EXPECT_LT(covered, n / 2);
    const Eigen::VectorXd b = Eigen::VectorXd::Random(n) * 1e5;
    Eigen::VectorXd x_whole(n), x = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
    two.solve(b, x_whole);
    two.forwardPart(0, b);
    two.forwardPart(1, b);
    two.solveSeparator(b, x);
    two.backwardPart(0, x, rt::SparseCholesky::Sweep::kFirst);
    two.backwardPart(1, x, rt::SparseCholesky::Sweep::kFirst);
    int differ = 0;
    for (const int g : dofs) differ += !(x(g) == x_whole(g));
    EXPECT_EQ(differ, 0) << "marked DOFs whose x differs after the first sweeps";
    two.backwardPart(0, x, rt::SparseCholesky::Sweep::kRest);
    two.backwardPart(1, x, rt::SparseCholesky::Sweep::kRest);
    differ = 0;
    for (int i = 0; i < n; ++i) differ += !(x(i) == x_whole(i));
    EXPECT_EQ(differ, 0) << "rows whose x differs from the whole solve";
    std::printf("[ figures  ] %s, %s: %zu DOFs marked, %d of %d rows solved first\n",
                rt::choleskyLayoutName(GetParam()), track == curve.get() ? "curve" : "straight", dofs.size(), covered,
                n);
  }
}

// kBlockedTwoParts solves in blocks where they are dense (the curve's window) and with the simplicial loops
// where a quarter of their values would be zeros (the straight's, whose rails' DOFs are partly uncoupled):
// both against CHOLMOD's solve, and the straight's phases on two threads equal to its whole solve.
TEST(SparseCholeskySolves, BlocksInTheCurveAndSimplicialLoopsOnTheStraight) {
  const std::unique_ptr<rt::CosimTrack> curve = curveWindowTrack();
  const std::unique_ptr<rt::CosimTrack> straight = curveWindowTrack(straightScene());
  for (const rt::CosimTrack* track : {curve.get(), straight.get()}) {
    const Eigen::SparseMatrix<double> K_eff = effectiveStiffness(*track);
    rt::SparseCholesky blocked(K_eff, rt::CholeskyLayout::kBlockedTwoParts);
    rt::SparseCholesky supernodal(K_eff, rt::CholeskyLayout::kSupernodal);
    EXPECT_EQ(blocked.solvesInBlocks(), track == curve.get());
    const int n = K_eff.rows();
    const Eigen::VectorXd b = Eigen::VectorXd::Random(n) * 1e5;
    Eigen::VectorXd x(n), x_ref(n), x_parts = Eigen::VectorXd::Zero(n);
    blocked.solve(b, x);
    supernodal.solve(b, x_ref);
    EXPECT_LT((x - x_ref).norm(), 1e-9 * x_ref.norm());
    solveInPhasesOnTwoThreads(blocked, b, x_parts);
    EXPECT_EQ((x_parts - x).cwiseAbs().maxCoeff(), 0.0);
    const rt::TrackMesh& mesh = track->trackWindow()->mesh();
    const int node = mesh.rail_nodes[0][mesh.rail_nodes[0].size() / 2];
    int dofs[6];
    for (int j = 0; j < 6; ++j) dofs[j] = mesh.dofIndex(node, j);
    Eigen::MatrixXd columns(n, 6);
    blocked.solveUnitColumns(dofs, 6, columns);
    for (int c = 0; c < 6; ++c) {
      Eigen::VectorXd e = Eigen::VectorXd::Zero(n), x_c(n);
      e(dofs[c]) = 1.0;
      supernodal.solve(e, x_c);
      EXPECT_LT((columns.col(c) - x_c).cwiseAbs().maxCoeff(), 1e-9 * x_c.cwiseAbs().maxCoeff()) << "column " << c;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(SparseCholeskySolves, TwoPartsLayout,
                         ::testing::Values(rt::CholeskyLayout::kSimplicialTwoParts,
                                           rt::CholeskyLayout::kBlockedTwoParts));
