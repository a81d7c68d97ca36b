// Moving active window of the flexible track (see track_window.hpp).
#include "rail_track_node/track_window.hpp"

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <sstream>
#include <stdexcept>
#include <utility>

#include <rail_contact/beam_shape.hpp>
#include <rail_contact/format.hpp>
#include <rail_core/scene_loader.hpp>

#include "rail_track_node/elements.hpp"
#include "rail_track_node/hanging_support.hpp"

namespace rail {
namespace track {

namespace rc = rail::contact;
using rail::contact::formatNumber;
using rail::core::SceneError;
using Clock = std::chrono::steady_clock;

namespace {

constexpr double kPi = 3.14159265358979323846;
// Slack on arc-length comparisons (m): far below any mesh spacing, far above round-off of s0 + k a.
constexpr double kSlack = 1e-9;
// Two meshes have the same matrices when every element's length, frame and arms agree to this (relative
// to 1 m / 1): round-off of the frame evaluation is ~1e-15, a real change of direction along a curve of
// radius R over a shift of l metres is l / R >= 1e-5 for any R below 100 km.
constexpr double kSameShape = 1e-10;

template <class A, class B>
bool near(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b) {
  return (a - b).template lpNorm<Eigen::Infinity>() <= kSameShape;
}

// True when mesh b is mesh a moved rigidly by a translation: same topology, element lengths, frames and
// spring arms, hence the same M, C, K and f_g.
bool sameShape(const TrackMesh& a, const TrackMesh& b) {
  if (a.nodes.size() != b.nodes.size() || a.beams.size() != b.beams.size() || a.springs.size() != b.springs.size() ||
      a.masses.size() != b.masses.size() || a.n_free_dofs != b.n_free_dofs)
    return false;
  for (std::size_t i = 0; i < a.beams.size(); ++i) {
    const BeamElement &p = a.beams[i], &q = b.beams[i];
    if (p.node_i != q.node_i || p.node_j != q.node_j || std::abs(p.length - q.length) > kSameShape ||
        !near(p.R_local_to_world, q.R_local_to_world))
      return false;
  }
  for (std::size_t i = 0; i < a.springs.size(); ++i) {
    const SpringDamperElement &p = a.springs[i], &q = b.springs[i];
    if (p.kind != q.kind || p.node_a != q.node_a || p.node_b != q.node_b || p.k != q.k || p.c != q.c ||
        p.unilateral != q.unilateral || p.gap != q.gap || !near(p.R_local_to_world, q.R_local_to_world) ||
        !near(p.p_point_in_world - a.nodes[p.node_a].p_in_world, q.p_point_in_world - b.nodes[q.node_a].p_in_world))
      return false;
    if (p.node_b >= 0 &&
        !near(p.p_point_in_world - a.nodes[p.node_b].p_in_world, q.p_point_in_world - b.nodes[q.node_b].p_in_world))
      return false;
  }
  for (std::size_t i = 0; i < a.masses.size(); ++i)
    if (a.masses[i].node != b.masses[i].node || a.masses[i].mass != b.masses[i].mass) return false;
  return true;
}

// Bays (whole, rounded up) needed for a length (m).
int baysFor(double length, double spacing) { return static_cast<int>(std::ceil(length / spacing - 1e-9)); }

}  // namespace

// One window: its model, the Newmark integrator over it (K_eff factor) and its self-weight static state.
struct TrackWindow::Window {
  int first_sleeper = 0;
  bool rear_cut = false, front_cut = false;  // artificial ends (condensed line beyond them)
  TrackModel model;
  std::unique_ptr<NewmarkIntegrator> integrator;
  Eigen::VectorXd d_static;
  std::unique_ptr<HangingSupports> hanging;  // hanging sleepers in the window (baseline d_static), or null
};

double movingLoadsLength(const rail::core::MovingLoads& loads) {
  if (loads.loads.empty()) return 0.0;
  double lo = loads.loads.front().offset, hi = lo;
  for (const rail::core::MovingLoad& l : loads.loads) {
    lo = std::min(lo, l.offset);
    hi = std::max(hi, l.offset);
  }
  return hi - lo;
}

TrackWindow::TrackWindow(TrackLine line, const TrackWindowSettings& settings, double s_rear, double s_front)
    : settings_(settings),
      geometry_(std::move(line.geometry)),
      data_(std::move(line.data)),
      g_in_world_(line.g_in_world) {
  const TrackWindowSettings& S = settings_;
  const std::string& source = line.source;
  auto refuse = [&source](const std::string& field, const std::string& what, double value) {
    throw std::runtime_error(source + ": track window: " + field + " " + what + ", got " + formatNumber(value));
  };
  if (!(S.behind >= 0.0) || !std::isfinite(S.behind)) refuse("behind", "must be finite and >= 0 m", S.behind);
  if (!(S.ahead >= 0.0) || !std::isfinite(S.ahead)) refuse("ahead", "must be finite and >= 0 m", S.ahead);
  if (const std::string why = rail::core::windowShiftRule(S.shift); !why.empty())
    throw std::runtime_error(source + ": track window: shift " + why);
  if (!(S.vehicle_length >= 0.0) || !std::isfinite(S.vehicle_length))
    refuse("vehicle_length", "must be finite and >= 0 m", S.vehicle_length);
  if (!(S.length >= 0.0) || !std::isfinite(S.length))
    refuse("length", "must be finite and >= 0 m (0: minimum)", S.length);
  track_step_ = S.track_step;
  if (const std::string why = rail::core::trackStepRule(track_step_); !why.empty())
    throw std::runtime_error(source + ": track window: track_step " + why);
  if (!(s_front >= s_rear) || !std::isfinite(s_rear) || !std::isfinite(s_front)) {
    std::ostringstream os;
    os << source << ": track window: the first wheel (s = " << s_front
       << " m) must not be behind the last one (s = " << s_rear << " m)";
    throw std::runtime_error(os.str());
  }

  line_ends_absorb_ = data_.absorbing_ends.enabled;
  c_end_.setZero();
  if (S.end_dashpots || line_ends_absorb_) {
    double k_lat = 0.0, k_vert = 0.0;
    foundationModuli(data_, k_lat, k_vert);
    if (!(data_.absorbing_ends.design_frequency > 0.0))
      throw SceneError(source +
                       ": track.data: absorbing_ends.design_frequency must be > 0 Hz for the window's "
                       "absorbing ends, got " +
                       formatNumber(data_.absorbing_ends.design_frequency));
    c_end_ = absorbingEndDashpots(data_.rail, k_lat, k_vert, 2.0 * kPi * data_.absorbing_ends.design_frequency);
  }
  data_.absorbing_ends.enabled = false;  // the window places its own end dashpots (buildWindow)
  seat_below_centre_ = seatPlaneBelowCentreLine(data_, line.rail_height);
  if (S.condensed_ends) {
    if (!(S.boundary_length >= data_.layout.sleeper_spacing) || !std::isfinite(S.boundary_length))
      refuse("boundary_length",
             "must be finite and at least one sleeper bay (" + formatNumber(data_.layout.sleeper_spacing) + " m)",
             S.boundary_length);
    const int nb = baysFor(S.boundary_length, data_.layout.sleeper_spacing);
    condensed_[0] = condenseEnd(data_, nb, false);
    condensed_[1] = condenseEnd(data_, nb, true);
  }

  const double a = data_.layout.sleeper_spacing;
  s_line_ = line.s_start;
  line_bays_ = static_cast<int>(std::floor(line.length / a + 1e-9));
  if (line_bays_ < 1)
    throw SceneError(source + ": track: the line is shorter than one sleeper bay (" + formatNumber(a) + " m), got " +
                     formatNumber(line.length));
  shift_bays_ = std::max(1, baysFor(S.shift, a));
  const int min_bays = std::max(1, baysFor(S.vehicle_length + S.behind + S.ahead + shift_bays_ * a, a));
  min_length_ = min_bays * a;
  int bays = min_bays;
  if (S.length > 0.0) {
    bays = baysFor(S.length, a);
    if (bays < min_bays) {
      std::ostringstream os;
      os << source << ": track window: length " << S.length << " m is shorter than the vehicle (" << S.vehicle_length
         << " m) + behind (" << S.behind << " m) + ahead (" << S.ahead << " m) + shift (" << shift_bays_ * a
         << " m); it needs at least " << min_length_ << " m (" << min_bays << " sleeper bays of " << a << " m)";
      throw std::runtime_error(os.str());
    }
  }
  window_bays_ = std::min(bays, line_bays_);  // a window as long as the line is the whole line

  // First window: its rear at the required rear (s_rear - behind), so that all the slack lies ahead.
  const int max_first = line_bays_ - window_bays_;
  int j0 = static_cast<int>(std::floor((s_rear - S.behind - s_line_) / a + kSlack));
  j0 = std::min(std::max(j0, 0), max_first);
  window_ = buildWindow(j0);
  const int n = window_->model.system.size();
  state_.d = Eigen::VectorXd::Zero(n);
  state_.v = Eigen::VectorXd::Zero(n);
  state_.a = Eigen::VectorXd::Zero(n);
  state_.t = 0.0;
  energy_scratch_.setZero(n);
  sizeHangingLoads();
  setRails();
  fillRails();
}

TrackWindow::~TrackWindow() = default;

std::unique_ptr<TrackWindow::Window> TrackWindow::buildWindow(int first_sleeper) const {
  const double a = data_.layout.sleeper_spacing;
  auto w = std::make_unique<Window>();
  w->first_sleeper = first_sleeper;
  w->rear_cut = first_sleeper > 0;
  w->front_cut = first_sleeper + window_bays_ < line_bays_;
  w->model.data = data_;
  MeshOptions mo;
  mo.s_start = s_line_ + first_sleeper * a;
  mo.track_length = window_bays_ * a;
  TrackMesh& mesh = w->model.mesh;
  mesh = buildTrackMesh(data_, mo, seatPlaneFrames(geometry_, seat_below_centre_));
  // Absorbing dashpots at the rail ends of each artificial end, and at the line's ends if the scene says so.
  const bool rear_cut = w->rear_cut, front_cut = w->front_cut;
  const bool rear = rear_cut ? settings_.end_dashpots : line_ends_absorb_;
  const bool front = front_cut ? settings_.end_dashpots : line_ends_absorb_;
  for (int r = 0; r < 2; ++r) {
    const BeamElement& first = mesh.beams[static_cast<std::size_t>(mesh.rail_beams[r].front())];
    const BeamElement& last = mesh.beams[static_cast<std::size_t>(mesh.rail_beams[r].back())];
    if (rear)
      mesh.springs.push_back(SpringDamperElement{SpringKind::AbsorbingEnd, first.node_i, -1,
                                                 mesh.nodes[static_cast<std::size_t>(first.node_i)].p_in_world,
                                                 first.R_local_to_world, Vector6d::Zero(), c_end_});
    if (front)
      mesh.springs.push_back(SpringDamperElement{SpringKind::AbsorbingEnd, last.node_j, -1,
                                                 mesh.nodes[static_cast<std::size_t>(last.node_j)].p_in_world,
                                                 last.R_local_to_world, Vector6d::Zero(), c_end_});
  }
  // Same shape as the current window (straight line: a translated copy): its matrices, factor and static
  // state are those of the current window; the caller moves them over.
  if (window_ && window_->rear_cut == rear_cut && window_->front_cut == front_cut &&
      sameShape(window_->model.mesh, mesh))
    return w;
  w->model.system = assembleLinearSystem(mesh, data_, g_in_world_);
  if (settings_.condensed_ends) {
    if (rear_cut) addCondensedEnd(*w, false);
    if (front_cut) addCondensedEnd(*w, true);
  }
  w->integrator = std::make_unique<NewmarkIntegrator>(w->model.system, track_step_, false, settings_.cost,
                                                      countEndDashpots(mesh), settings_.factor_layout);
  // The self-weight state of a window with hanging sleepers is that of the piecewise-linear track; w then
  // integrates from it, with the hanging loads relative to it.
  auto hanging = std::make_unique<HangingSupports>(mesh);
  const Eigen::VectorXd f_g =
      settings_.include_gravity ? w->model.system.f_gravity : Eigen::VectorXd::Zero(w->model.system.size());
  if (hanging->empty()) {
    w->d_static = settings_.include_gravity ? staticGravityDeflection(w->model.system) : f_g;
  } else {
    w->d_static = hanging->solveStatic(w->model.system, f_g);
    hanging->setBaseline(w->d_static);
    w->hanging = std::move(hanging);
  }
  return w;
}

namespace {

// The 8 free nodes of sleeper plane k (6 sleeper nodes right to left, left rail node, right rail node).
std::array<int, 8> planeNodes(const TrackMesh& mesh, int k) {
  std::array<int, 8> p;
  for (int q = 0; q < 6; ++q)
    p[static_cast<std::size_t>(q)] = mesh.sleeper_nodes[static_cast<std::size_t>(k)][static_cast<std::size_t>(q)];
  for (int r = 0; r < 2; ++r)
    p[static_cast<std::size_t>(6 + r)] =
        mesh.rail_nodes[r][static_cast<std::size_t>(k * mesh.rail_elements_between_sleepers)];
  return p;
}

}  // namespace

TrackWindow::CondensedEnd TrackWindow::condenseEnd(const TrackData& data, int bays, bool front) {
  // A straight level piece in track axes (world = track frame). front: the line ahead of an end plane,
  // which is the piece's first plane; else the line behind it, the piece's last plane.
  // The line beyond an end is the data's plain track: support zones act inside the window only.
  TrackData plain = data;
  plain.support_zones.clear();
  MeshOptions mo;
  mo.s_start = 0.0;
  mo.track_length = bays * data.layout.sleeper_spacing;
  TrackMesh mesh = buildTrackMesh(plain, mo, straightTrackFrames());
  CondensedEnd e;
  e.piece = mesh;
  const int kb = front ? 0 : mesh.n_sleepers - 1;
  const std::array<int, 8> plane = planeNodes(mesh, kb);
  // Nodes of the plane itself (its foundation nodes are fixed): elements among them belong to the window.
  std::vector<char> in_plane(mesh.nodes.size(), 0);
  for (int nd : plane) in_plane[static_cast<std::size_t>(nd)] = 1;
  auto own = [&](int nd) {
    return nd < 0 || in_plane[static_cast<std::size_t>(nd)] || mesh.nodes[static_cast<std::size_t>(nd)].fixed;
  };
  std::vector<BeamElement> beams;
  for (const BeamElement& b : mesh.beams)
    if (!(in_plane[static_cast<std::size_t>(b.node_i)] && in_plane[static_cast<std::size_t>(b.node_j)]))
      beams.push_back(b);
  std::vector<SpringDamperElement> springs;
  for (const SpringDamperElement& sp : mesh.springs)
    if (!(in_plane[static_cast<std::size_t>(sp.node_a)] && own(sp.node_b))) springs.push_back(sp);
  std::vector<PointMass> masses;
  for (const PointMass& pm : mesh.masses)
    if (!in_plane[static_cast<std::size_t>(pm.node)]) masses.push_back(pm);
  mesh.beams = std::move(beams);
  mesh.springs = std::move(springs);
  mesh.masses = std::move(masses);
  const LinearSystem out = assembleLinearSystem(mesh, data, Eigen::Vector3d::Zero());

  // Boundary DOFs b (the plane's 48) first, interior DOFs i after.
  const int n = mesh.n_free_dofs, nb = 48, ni = n - nb;
  std::vector<int> pos(static_cast<std::size_t>(n), -1);  // b: 0..47; i: 48..n-1
  for (int q = 0; q < 8; ++q)
    for (int j = 0; j < 6; ++j)
      pos[static_cast<std::size_t>(mesh.dofIndex(plane[static_cast<std::size_t>(q)], j))] = 6 * q + j;
  int next = nb;
  for (int i = 0; i < n; ++i)
    if (pos[static_cast<std::size_t>(i)] < 0) pos[static_cast<std::size_t>(i)] = next++;
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> P(n);
  for (int i = 0; i < n; ++i) P.indices()(i) = pos[static_cast<std::size_t>(i)];
  auto permuted = [&P](const Eigen::SparseMatrix<double>& A) {
    Eigen::SparseMatrix<double> B;
    B = P * A * P.transpose();  // row and column i of A -> pos(i)
    return B;
  };
  const Eigen::SparseMatrix<double> K = permuted(out.K), C = permuted(out.C), M = permuted(out.M);
  const Eigen::SparseMatrix<double> K_ii = K.bottomRightCorner(ni, ni);
  const Eigen::MatrixXd K_ib = Eigen::MatrixXd(K.bottomLeftCorner(ni, nb));
  Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> llt(K_ii);
  if (llt.info() != Eigen::Success)
    throw std::runtime_error(
        "track window: the track beyond a window end is not supported (K_ii not positive definite)");
  // Static shapes: the interior's static response to each boundary DOF, x = [I; Phi].
  Eigen::MatrixXd X(n, nb);
  X.topRows(nb).setIdentity();
  X.bottomRows(ni) = -llt.solve(K_ib);
  e.K = X.transpose() * (K * X);
  e.C = X.transpose() * (C * X);
  e.M = X.transpose() * (M * X);
  e.K = 0.5 * (e.K + e.K.transpose()).eval();
  e.C = 0.5 * (e.C + e.C.transpose()).eval();
  e.M = 0.5 * (e.M + e.M.transpose()).eval();
  // Self-weight of the outside per unit gravity along each axis: u = unit translation of every node.
  Eigen::MatrixXd U = Eigen::MatrixXd::Zero(n, 3);
  for (std::size_t nd = 0; nd < mesh.nodes.size(); ++nd)
    for (int j = 0; j < 3; ++j) {
      const int i = mesh.dofIndex(static_cast<int>(nd), j);
      if (i >= 0) U(pos[static_cast<std::size_t>(i)], j) = 1.0;
    }
  e.G = X.transpose() * (M * U);
  e.pos = std::move(pos);
  e.X = std::move(X);
  return e;
}

void TrackWindow::addCondensedEnd(Window& w, bool front) const {
  const CondensedEnd& e = condensed_[front ? 1 : 0];
  TrackMesh& mesh = w.model.mesh;
  LinearSystem& sys = w.model.system;
  const int k = front ? mesh.n_sleepers - 1 : 0;
  const std::array<int, 8> plane = planeNodes(mesh, k);
  rc::TrackPoint tp;
  geometry_.centre(mesh.s_start + k * mesh.sleeper_spacing, tp);
  const Eigen::Matrix3d& R = tp.R_track_to_world;
  // B: track-axis DOFs of the plane -> world-axis DOFs (3 x 3 blocks R).
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(48, 48);
  for (int q = 0; q < 16; ++q) B.block<3, 3>(3 * q, 3 * q) = R;
  std::array<int, 48> dofs;
  for (int q = 0; q < 8; ++q)
    for (int j = 0; j < 6; ++j)
      dofs[static_cast<std::size_t>(6 * q + j)] = mesh.dofIndex(plane[static_cast<std::size_t>(q)], j);
  auto add = [&](Eigen::SparseMatrix<double>& A, const Eigen::MatrixXd& local) {
    const Eigen::MatrixXd world = B * local * B.transpose();
    std::vector<Eigen::Triplet<double>> t;
    t.reserve(48 * 48);
    for (int r = 0; r < 48; ++r)
      for (int c = 0; c < 48; ++c)
        if (world(r, c) != 0.0)
          t.emplace_back(dofs[static_cast<std::size_t>(r)], dofs[static_cast<std::size_t>(c)], world(r, c));
    Eigen::SparseMatrix<double> S(A.rows(), A.cols());
    S.setFromTriplets(t.begin(), t.end());
    A += S;
    A.makeCompressed();
  };
  add(sys.K, e.K);
  add(sys.C, e.C);
  add(sys.M, e.M);
  const Eigen::VectorXd f = B * (e.G * (R.transpose() * g_in_world_));
  for (int r = 0; r < 48; ++r) sys.f_gravity(dofs[static_cast<std::size_t>(r)]) += f(r);
}

void TrackWindow::moveTo(int first_sleeper) {
  const Clock::time_point t0 = Clock::now();
  std::unique_ptr<Window> next = buildWindow(first_sleeper);
  const int m = first_sleeper - window_->first_sleeper;  // bays moved (> 0 forward)
  const TrackMesh& old_mesh = window_->model.mesh;
  const TrackMesh& new_mesh = next->model.mesh;
  const int n_e = new_mesh.rail_elements_between_sleepers;

  // w, w', w'' of the nodes in both windows (same line index: rail node k <-> k + m n_e, sleeper k <-> k + m);
  // entering nodes start at rest here, then (entering_static) at the static continuation of the rest.
  const int n = new_mesh.n_free_dofs;
  NewmarkState next_state;
  next_state.d = Eigen::VectorXd::Zero(n);
  next_state.v = Eigen::VectorXd::Zero(n);
  next_state.a = Eigen::VectorXd::Zero(n);
  next_state.t = state_.t;
  std::vector<char> carried(static_cast<std::size_t>(n), 0);
  auto copyNode = [&](int node_new, int node_old) {
    for (int j = 0; j < 6; ++j) {
      const int i_new = new_mesh.dofIndex(node_new, j), i_old = old_mesh.dofIndex(node_old, j);
      if (i_new < 0 || i_old < 0) continue;
      carried[static_cast<std::size_t>(i_new)] = 1;
      next_state.d(i_new) = state_.d(i_old);
      next_state.v(i_new) = state_.v(i_old);
      next_state.a(i_new) = state_.a(i_old);
    }
  };
  for (int r = 0; r < 2; ++r) {
    const int count = static_cast<int>(new_mesh.rail_nodes[r].size());
    for (int k = 0; k < count; ++k) {
      const int k_old = k + m * n_e;
      if (k_old >= 0 && k_old < count)
        copyNode(new_mesh.rail_nodes[r][static_cast<std::size_t>(k)],
                 old_mesh.rail_nodes[r][static_cast<std::size_t>(k_old)]);
    }
  }
  const int n_s = new_mesh.n_sleepers;
  for (int k = 0; k < n_s; ++k) {
    const int k_old = k + m;
    if (k_old < 0 || k_old >= n_s) continue;
    for (int q = 0; q < 6; ++q)
      copyNode(new_mesh.sleeper_nodes[static_cast<std::size_t>(k)][static_cast<std::size_t>(q)],
               old_mesh.sleeper_nodes[static_cast<std::size_t>(k_old)][static_cast<std::size_t>(q)]);
  }

  if (!next->integrator) {
    // Same matrices: keep the current system, factor and static state; take the new mesh (positions).
    window_->model.mesh = std::move(next->model.mesh);
    window_->first_sleeper = first_sleeper;  // same cut flags (buildWindow)
  } else {
    window_ = std::move(next);
    ++stats_.rebuilds;
  }
  if (settings_.entering_static) extrapolateEntering(carried, next_state);
  state_ = std::move(next_state);
  sizeHangingLoads();
  setRails();
  fillRails();
  placeSections();
  ++stats_.shifts;
  stats_.last_shift_s = std::chrono::duration<double>(Clock::now() - t0).count();
  stats_.total_shift_s += stats_.last_shift_s;
}

void TrackWindow::extrapolateEntering(const std::vector<char>& carried, NewmarkState& st) const {
  // Entering DOFs e, carried DOFs c: K_ee x_e = -K_ec x_c for x = w, w', w'' (the static continuation of the
  // carried field into the entering nodes, with the new window's K).
  const Eigen::SparseMatrix<double>& K = window_->model.system.K;
  const int n = static_cast<int>(K.rows());
  std::vector<int> pos(static_cast<std::size_t>(n), -1);
  int n_e = 0;
  for (int i = 0; i < n; ++i)
    if (!carried[static_cast<std::size_t>(i)]) pos[static_cast<std::size_t>(i)] = n_e++;
  if (n_e == 0 || n_e == n) return;
  std::vector<Eigen::Triplet<double>> trip;
  for (int col = 0; col < K.outerSize(); ++col) {
    if (pos[static_cast<std::size_t>(col)] < 0) continue;
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, col); it; ++it)
      if (pos[static_cast<std::size_t>(it.row())] >= 0)
        trip.emplace_back(pos[static_cast<std::size_t>(it.row())], pos[static_cast<std::size_t>(col)], it.value());
  }
  Eigen::SparseMatrix<double> K_ee(n_e, n_e);
  K_ee.setFromTriplets(trip.begin(), trip.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(K_ee);
  if (ldlt.info() != Eigen::Success) return;  // cannot happen for a supported track; keep the rest state
  Eigen::VectorXd r(n), r_e(n_e);
  for (Eigen::VectorXd* x : {&st.d, &st.v, &st.a}) {
    r.noalias() = K * (*x);  // entering entries of x are zero: r_e = K_ec x_c
    for (int i = 0; i < n; ++i)
      if (pos[static_cast<std::size_t>(i)] >= 0) r_e(pos[static_cast<std::size_t>(i)]) = -r(i);
    const Eigen::VectorXd x_e = ldlt.solve(r_e);
    for (int i = 0; i < n; ++i)
      if (pos[static_cast<std::size_t>(i)] >= 0) (*x)(i) = x_e(pos[static_cast<std::size_t>(i)]);
  }
}

bool TrackWindow::holds(double s_rear, double s_front) const {
  return s_rear - settings_.behind >= sBegin() - kSlack && s_front + settings_.ahead <= sEnd() + kSlack;
}

void TrackWindow::setCostClock(rail::core::CostClock* cost) {
  settings_.cost = cost;
  window_->integrator->setCostClock(cost);
}

bool TrackWindow::follow(double s_rear, double s_front) {
  const double lo = s_rear - settings_.behind, hi = s_front + settings_.ahead;
  const double begin = sBegin(), end = sEnd();
  if (lo >= begin - kSlack && hi <= end + kSlack) return false;
  const double step = shift_bays_ * data_.layout.sleeper_spacing;
  const int j0 = window_->first_sleeper;
  int j = j0;
  if (hi > end + kSlack)
    j = j0 + shift_bays_ * static_cast<int>(std::ceil((hi - end) / step - kSlack));
  else
    j = j0 - shift_bays_ * static_cast<int>(std::ceil((begin - lo) / step - kSlack));
  j = std::min(std::max(j, 0), line_bays_ - window_bays_);
  if (j == j0) return false;  // at the line's end
  moveTo(j);
  return true;
}

void TrackWindow::step(const NodalLoads& loads) noexcept {
  if (window_->hanging) {
    hanging_loads_.clear();
    window_->hanging->addLoads(state_.d, state_.v, &window_->d_static, track_step_, hanging_loads_);
    window_->integrator->step(state_, loads, &hanging_loads_);
  } else {
    window_->integrator->step(state_, loads);
  }
  finishStep();
}

const HangingSupports* TrackWindow::hanging() const { return window_->hanging.get(); }

void TrackWindow::sizeHangingLoads() {
  const int need = window_->hanging ? window_->hanging->loadCapacity() : 0;
  if (hanging_loads_.capacity() < need) hanging_loads_ = NodalLoads(need);
}

NewmarkIntegrator& TrackWindow::integrator() { return *window_->integrator; }

void TrackWindow::finishStep() noexcept {
  ++stats_.steps;
  rails_current_ = false;  // filled when next read (railDeformation())
}

void TrackWindow::setStaticState(const NodalLoads& loads) {
  const LinearSystem& sys = window_->model.system;
  Eigen::VectorXd f = Eigen::VectorXd::Zero(sys.size());
  for (int k = 0; k < loads.size(); ++k) f(loads.index(k)) += loads.value(k);
  if (window_->hanging) {
    // The piecewise-linear track: d_g + w its static state under self-weight and the loads.
    if (settings_.include_gravity) f += sys.f_gravity;
    state_.d = window_->hanging->solveStatic(sys, f) - window_->d_static;
  } else {
    state_.d = solveStatic(sys, f);
  }
  state_.v.setZero();
  state_.a.setZero();
  fillRails();
}

double TrackWindow::sBegin() const { return s_line_ + window_->first_sleeper * data_.layout.sleeper_spacing; }
double TrackWindow::sEnd() const {
  return s_line_ + (window_->first_sleeper + window_bays_) * data_.layout.sleeper_spacing;
}
int TrackWindow::firstSleeper() const { return window_->first_sleeper; }
const TrackModel& TrackWindow::model() const { return window_->model; }
const Eigen::VectorXd& TrackWindow::staticState() const { return window_->d_static; }

double TrackWindow::dynamicEnergy() const {
  double kinetic = 0.0, potential = 0.0;
  dynamicEnergy(kinetic, potential);
  return kinetic + potential;
}

void TrackWindow::dynamicEnergy(double& kinetic, double& potential) const {
  const LinearSystem& sys = window_->model.system;
  energy_scratch_.noalias() = sys.M * state_.v;
  kinetic = 0.5 * state_.v.dot(energy_scratch_);
  energy_scratch_.noalias() = sys.K * state_.d;
  potential = 0.5 * state_.d.dot(energy_scratch_);
}

// The rails of `mesh` as the contact search sees them: one BeamRailDeformation element per FE rail beam
// (nodes equally spaced in s) and, per rail, the free DOF of (rail node k, dof j) at 6 k + j. An existing
// deformation object is kept and its layout rebuilt in place (set-up and window moves; allocates).
void buildRailLayout(const TrackMesh& mesh, std::array<std::vector<int>, 2>& rail_dofs,
                     std::unique_ptr<rc::BeamRailDeformation>& deformation) {
  std::array<std::vector<rc::RailBeamElement>, 2> elements;
  for (int r = 0; r < 2; ++r) {
    for (int b : mesh.rail_beams[r]) {
      rc::RailBeamElement e;
      e.length = mesh.beams[static_cast<std::size_t>(b)].length;
      e.R_local_to_world = mesh.beams[static_cast<std::size_t>(b)].R_local_to_world;
      elements[r].push_back(e);
    }
    rail_dofs[r].resize(6 * mesh.rail_nodes[r].size());
    for (std::size_t k = 0; k < mesh.rail_nodes[r].size(); ++k)
      for (int j = 0; j < 6; ++j) rail_dofs[r][6 * k + j] = mesh.dofIndex(mesh.rail_nodes[r][k], j);
  }
  rc::BeamRailDeformation rails(mesh.s_start, mesh.sleeper_spacing / mesh.rail_elements_between_sleepers,
                                std::move(elements));
  if (deformation)
    *deformation = std::move(rails);
  else
    deformation = std::make_unique<rc::BeamRailDeformation>(std::move(rails));
}

void TrackWindow::setRails() { buildRailLayout(window_->model.mesh, rail_dofs_, deformation_); }

void fillRailArrays(const std::array<std::vector<int>, 2>& rail_dofs, const Eigen::VectorXd& d,
                    const Eigen::VectorXd& v, const Eigen::VectorXd* d_static, double dt,
                    rc::BeamRailDeformation& deformation) noexcept {
  for (int r = 0; r < 2; ++r) {
    const rc::RailSide side = r == 0 ? rc::RailSide::kLeft : rc::RailSide::kRight;
    double* q = deformation.nodalDisplacements(side);
    double* qd = deformation.nodalVelocities(side);
    const std::vector<int>& dofs = rail_dofs[static_cast<std::size_t>(r)];
    for (std::size_t i = 0; i < dofs.size(); ++i) {
      const int g = dofs[i];
      if (g < 0) {
        q[i] = qd[i] = 0.0;
        continue;
      }
      q[i] = d(g) + dt * v(g);
      if (d_static != nullptr) q[i] += (*d_static)(g);
      qd[i] = v(g);
    }
  }
}

void TrackWindow::fillRails() const noexcept {
  fillRailArrays(rail_dofs_, state_.d, state_.v, &window_->d_static, 0.0, *deformation_);
  rails_current_ = true;
}

void TrackWindow::placeSection(Section& sec) const {
  rc::TrackPoint tp;
  geometry_.centre(sec.arc_length, tp);
  const TrackMesh& mesh = window_->model.mesh;
  sec.inside = sec.arc_length >= sBegin() - kSlack && sec.arc_length <= sEnd() + kSlack &&
               makeRailProbes(mesh, tp.R_track_to_world, sec.arc_length, sec.rail);
  sec.beyond = false;
  if (sec.inside || !settings_.condensed_ends) return;
  const bool front = sec.arc_length > sEnd();
  if (front ? window_->first_sleeper + window_bays_ >= line_bays_ : window_->first_sleeper <= 0) return;  // line end
  const CondensedEnd& e = condensed_[front ? 1 : 0];
  const double piece_length = e.piece.n_sleepers > 0 ? (e.piece.n_sleepers - 1) * e.piece.sleeper_spacing : 0.0;
  const double x = front ? sec.arc_length - sEnd() : sBegin() - sec.arc_length;  // distance beyond the end plane, m
  if (!(x <= piece_length)) return;                                              // beyond the condensed piece: at rest
  RailProbes piece_probe;
  if (!makeRailProbes(e.piece, Eigen::Matrix3d::Identity(), front ? x : piece_length - x, piece_probe)) return;
  // End plane of the window, its track frame, and the rotation from it to the frame at the section.
  const int k = front ? mesh.n_sleepers - 1 : 0;
  const std::array<int, 8> plane = planeNodes(mesh, k);
  for (int q = 0; q < 8; ++q)
    for (int j = 0; j < 6; ++j)
      sec.plane_dofs[static_cast<std::size_t>(6 * q + j)] = mesh.dofIndex(plane[static_cast<std::size_t>(q)], j);
  rc::TrackPoint end;
  geometry_.centre(mesh.s_start + k * mesh.sleeper_spacing, end);
  const Eigen::Matrix3d R_end_to_section = tp.R_track_to_world.transpose() * end.R_track_to_world;
  Eigen::Matrix<double, 48, 48> Bt = Eigen::Matrix<double, 48, 48>::Zero();  // world -> end track axes
  for (int q = 0; q < 16; ++q) Bt.block<3, 3>(3 * q, 3 * q) = end.R_track_to_world.transpose();
  for (int r = 0; r < 2; ++r) {
    const RailProbe& p = piece_probe[static_cast<std::size_t>(r)];
    Eigen::Matrix<double, 12, 48> Xe = Eigen::Matrix<double, 12, 48>::Zero();
    for (int d = 0; d < 12; ++d) {
      const int i = p.dofs[static_cast<std::size_t>(d)];
      if (i >= 0) Xe.row(d) = e.X.row(e.pos[static_cast<std::size_t>(i)]);
    }
    sec.Q_u[static_cast<std::size_t>(r)] = R_end_to_section * p.P_u * Xe * Bt;
    sec.Q_theta[static_cast<std::size_t>(r)] = R_end_to_section * p.P_theta * Xe * Bt;
  }
  sec.beyond = true;
}

void TrackWindow::placeSections() {
  for (Section& sec : sections_) placeSection(sec);
}

int TrackWindow::addSection(double s, double static_half_length) {
  const double a = data_.layout.sleeper_spacing;
  const double s_last = s_line_ + line_bays_ * a;
  if (!(s >= s_line_ - kSlack && s <= s_last + kSlack)) {
    std::ostringstream os;
    os << "track window: deflection section at s = " << s << " m is not on the meshable line [" << s_line_ << ", "
       << s_last << "] m";
    throw std::runtime_error(os.str());
  }
  if (!(static_half_length > 0.0)) {
    std::ostringstream os;
    os << "track window: static_half_length of the section at s = " << s << " m must be > 0 m, got "
       << static_half_length;
    throw std::runtime_error(os.str());
  }
  Section sec;
  sec.arc_length = s;
  sec.static_value.arc_length = s;
  for (int r = 0; r < 2; ++r) {
    sec.static_value.displacement[static_cast<std::size_t>(r)].setZero();
    sec.static_value.rotation[static_cast<std::size_t>(r)].setZero();
  }
  if (settings_.include_gravity) {
    // Self-weight static state at s from a line piece around it (the line's own ends where it reaches them).
    const int j_lo = std::max(0, static_cast<int>(std::floor((s - static_half_length - s_line_) / a)));
    const int j_hi = std::min(line_bays_, static_cast<int>(std::ceil((s + static_half_length - s_line_) / a)));
    MeshOptions mo;
    mo.s_start = s_line_ + j_lo * a;
    mo.track_length = (j_hi - j_lo) * a;
    const TrackModel piece = buildTrackModel(data_, mo, seatPlaneFrames(geometry_, seat_below_centre_), g_in_world_);
    RailProbes probes;
    rc::TrackPoint tp;
    geometry_.centre(s, tp);
    makeRailProbes(piece.mesh, tp.R_track_to_world, s, probes);
    evalRailProbes(probes, solveStaticWithSupports(piece.mesh, piece.system, piece.system.f_gravity), sec.static_value);
  }
  placeSection(sec);
  sections_.push_back(sec);
  return static_cast<int>(sections_.size()) - 1;
}

void TrackWindow::sectionDynamicDeflection(int i, RailSectionDeflection& out) const {
  const Section& sec = sections_[static_cast<std::size_t>(i)];
  out.arc_length = sec.arc_length;
  if (sec.inside) {
    evalRailProbes(sec.rail, state_.d, out);
  } else if (sec.beyond) {
    Eigen::Matrix<double, 48, 1> w_b;
    for (int k = 0; k < 48; ++k) w_b(k) = state_.d(sec.plane_dofs[static_cast<std::size_t>(k)]);
    for (int r = 0; r < 2; ++r) {
      out.displacement[static_cast<std::size_t>(r)].noalias() = sec.Q_u[static_cast<std::size_t>(r)] * w_b;
      out.rotation[static_cast<std::size_t>(r)].noalias() = sec.Q_theta[static_cast<std::size_t>(r)] * w_b;
    }
  } else {
    for (int r = 0; r < 2; ++r) {
      out.displacement[static_cast<std::size_t>(r)].setZero();
      out.rotation[static_cast<std::size_t>(r)].setZero();
    }
  }
}

void TrackWindow::sectionDeflection(int i, RailSectionDeflection& out) const {
  sectionDynamicDeflection(i, out);
  const RailSectionDeflection& st = sections_[static_cast<std::size_t>(i)].static_value;
  for (int r = 0; r < 2; ++r) {
    out.displacement[static_cast<std::size_t>(r)] += st.displacement[static_cast<std::size_t>(r)];
    out.rotation[static_cast<std::size_t>(r)] += st.rotation[static_cast<std::size_t>(r)];
  }
}

}  // namespace track
}  // namespace rail
