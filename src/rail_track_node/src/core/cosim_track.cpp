// Track side of the co-simulation (see cosim_track.hpp).
#include "rail_track_node/cosim_track.hpp"
#include "rail_track_node/hanging_support.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>

#include <rail_contact/beam_shape.hpp>
#include <rail_contact/format.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/scene_loader.hpp>

#include "rail_track_node/elements.hpp"

namespace rail {
namespace track {

namespace rc = rail::contact;
namespace cc = rail::core::coupling;
using rail::core::Scene;
using rail::core::SceneError;

namespace {

// How long a thread of the step waits awake (spinning) for the other before it sleeps on the condition
// variable: a futex wake-up costs 10-50 us here, a track step a few hundred. The worker waits for its
// next job through the Newton solve, and the loop's thread for the base solve after its contacts; both
// while the vehicle node waits for the track. The two threads complete a step together, half of the DOFs
// each, and each waits awake for the other's half.
constexpr std::chrono::microseconds kJobSpin{400}, kSolveSpin{400};

// Moves the Newmark parts (right-hand side, solve) and the counts of `from` into `to`.
void addClock(rail::core::CostClock& from, rail::core::CostClock& to) noexcept {
  for (int p : {rail::core::CostClock::kTrackRhs, rail::core::CostClock::kTrackSolve}) {
    to.seconds[static_cast<std::size_t>(p)] += from.seconds[static_cast<std::size_t>(p)];
    to.calls[static_cast<std::size_t>(p)] += from.calls[static_cast<std::size_t>(p)];
    from.seconds[static_cast<std::size_t>(p)] = 0.0;
    from.calls[static_cast<std::size_t>(p)] = 0;
  }
  for (std::size_t c = 0; c < from.counts.size(); ++c) {
    to.counts[c] += from.counts[c];
    from.counts[c] = 0;
  }
}

// y += a x over n entries, compiled for AVX2 where the CPU has it and for the baseline: each entry one
// multiply and one add either way (no fused multiply-add), so the same bits.
__attribute__((target_clones("avx2", "default"))) void addScaledColumn(double* y, const double* x, double a,
                                                                       int n) noexcept {
  for (int i = 0; i < n; ++i) y[i] += a * x[i];
}

bool awaitFlag(const std::atomic<bool>& flag, bool value, std::chrono::microseconds budget) noexcept {
  const auto until = std::chrono::steady_clock::now() + budget;
  for (int i = 1;; ++i) {
    if (flag.load(std::memory_order_acquire) == value) return true;
    __builtin_ia32_pause();
    if (i % 32 == 0 && std::chrono::steady_clock::now() > until) return false;
  }
}

// The contact forces' share of a step (Newton, influence columns and their loads): added to the contact
// clock, when there is one, at the end of the scope.
class ForcesTime {
 public:
  explicit ForcesTime(rc::ContactCost* cost) : cost_(cost) {
    if (cost_ != nullptr) t0_ = std::chrono::steady_clock::now();
  }
  ~ForcesTime() {
    if (cost_ != nullptr)
      cost_->forces_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }
  ForcesTime(const ForcesTime&) = delete;
  ForcesTime& operator=(const ForcesTime&) = delete;

 private:
  rc::ContactCost* cost_;
  std::chrono::steady_clock::time_point t0_;
};
constexpr int kNodeDofs = 6;
using Vector12d = rc::Vector12d;

}  // namespace

// Semi-implicit coupling state (flexible, kSemiImplicit). Everything is sized at construction.
//
// Influence columns: for the free DOF g of a rail node, a_g = K_eff^{-1} e_g, stored over the window of DOF
// indices where |a_g| > tolerance * max |a_g| (the response to a point load decays within metres of
// rail; the DOFs are numbered plane by plane along the track). Slots hold the 6 columns of one rail node;
// a wheel needs the 2 nodes of each contact element, so 4 slots per wheel are never short; a slot is
// reused least-recently-used when a wheel reaches a node not cached.
struct CosimTrack::Implicit {
  int n = 0;       // free DOFs
  int window = 0;  // column capacity, entries
  double tolerance = 1e-12;
  int slots = 0;
  std::vector<double> values;                                              // slot-major: (slot * 6 + j) * window
  std::vector<int> lo, len;                                                // per column: first DOF index, entries
  std::vector<int> slot_rail, slot_node;                                   // key of each slot (-1 free)
  std::vector<long> slot_used;                                             // frame of last use
  std::array<std::vector<int>, 2> node_slot;                               // per rail node: its slot or -1
  Eigen::VectorXd unit, column;                                            // solve scratch
  std::array<Eigen::MatrixXd, SparseCholesky::kColumnLanes> node_columns;  // per lane: one node's 6 columns (n x 6)
  std::atomic<long> solves{0}, clipped{0};
  std::vector<int> pending;  // slots claimed this frame whose columns are still to be solved

  // Contact law at rail contact-point displacement u (eq. 9, creepages, Polach), results into out.
  struct LawOut {
    Eigen::Vector3d F_wheel = Eigen::Vector3d::Zero();
    double N = 0.0, F_long = 0.0, F_lat = 0.0, a = 0.0, b = 0.0, delta = 0.0, delta_dot = 0.0;
    double nu_x = 0.0, nu_y = 0.0, phi = 0.0;
  };
  // One contact of this step in the implicit solve: its geometry (point, frame, Hertz and Kalker data)
  // frozen at the predicted state, its force a function of the rail contact point's motion u (world).
  struct Link {
    int frame_index = 0, wheel = 0, contact = 0, rail = 0, element = 0;
    std::array<int, 12> dofs{};      // free DOFs of the element (node q then q + 1), -1 fixed
    Eigen::Matrix<double, 12, 3> W;  // nodal loads of unit world forces at the rail contact point; W' d_e = u
    Eigen::Matrix3d R_contact_to_world;
    Eigen::Vector3d v_wheel, v_rail_p, omega_wheel, omega_rail_p;  // material-point / body velocities
    double V_p = 0.0;                                              // rolling speed of the evaluation, m/s
    double K = 0.0, a_coeff = 0.0, b_coeff = 0.0;                  // N = K delta^n (1 + ...); a = a_coeff N^(1/3)
    rail::contact::KalkerCoefficients kalker;
    double v_impact = 0.0, delta_p = 0.0;
    Eigen::Vector3d u_p, u0, base_dot;  // W'd_p; W'x0; u_dot = (2/h) u - base_dot
    Eigen::Vector3d f_p, f;             // force on the rail at the prediction (its loads are in x0) and now, N
    Eigen::Vector3d u, u_start, du;     // Newton iterate of the rail contact-point displacement, m
    Eigen::Vector3d F_wheel, R;         // law's force on the wheel at u; residual of u, m
    LawOut at_u;                        // the law at u (its force is F_wheel)
    Eigen::Matrix3d J;                  // d F_wheel / d u (Newmark velocity included), N/m
  };
  std::vector<Link> links;          // capacity kContactSlots per wheel
  std::vector<double> column_load;  // per cached column: the nodal load on its DOF this step, N
  std::vector<unsigned char> column_used;
  std::vector<int> used_columns;        // columns with a load this step (capacity all of them)
  std::vector<Eigen::Vector3d> memory;  // per (wheel, contact): K, a_coeff, b_coeff last seen with N > 0
  Eigen::MatrixXd G, S;                 // W_c' K_eff^{-1} W_e (3 x 3 blocks) and the Newton matrix, 3 per link
  Eigen::VectorXd rhs;
  // Links that load each other (a nonzero G block, directly or through others) form a group; the links of
  // group q are order[group_start[q]] .. order[group_start[q + 1] - 1], ascending. Far-apart bogies do
  // not see each other through the truncated columns, so the Newton matrix is solved group by group.
  std::vector<int> group_of, order, group_start, group_index;  // group_index: each link's group q
  int groups = 0;
  // Per slot: bumped whenever the slot's columns change (a new node, a dropped cache), so that what was read
  // from them is known to be current.
  std::vector<long> slot_generation;
  // K_eff^{-1} between the 12 DOFs of a link's element (rows) and those of another's (columns), as read from
  // the columns of the second, per pair of (wheel, contact) keys: a pair whose elements and columns are
  // those of an earlier step reuses the values instead of reading them again from the columns.
  struct PairBlock {
    int rail_c = -1, element_c = -1, slot_0 = -1, slot_1 = -1;  // slot and generation name the column's node
    long generation_0 = -1, generation_1 = -1;
    std::array<double, 144> a{};  // column j (12), row i (12): a[12 j + i]; 0 where the row is fixed
  };
  std::vector<PairBlock> pair_blocks;  // (kContactSlots * wheel + contact) of the row link, then of the column link
  int keys = 0;                        // kContactSlots * wheels
  rail::contact::PolachOptions polach;
  long newton_iterations = 0, unconverged = 0;
  rail::contact::ContactCost* cost = nullptr;  // creep evaluations of law() (CosimTrackOptions::cost)

  void law(const rail::contact::WheelContactModel& model, double h, const Link& L, const Eigen::Vector3d& u,
           LawOut& o) const noexcept;
  const std::array<double, 144>& pairBlock(const Link& Lc, const Link& Le) noexcept;
  // f(e) for each link e of link c's group, ascending (G is zero between groups).
  template <class F>
  void forGroupOf(int c, F f) const {
    const std::size_t q = static_cast<std::size_t>(group_index[static_cast<std::size_t>(c)]);
    for (int k = group_start[q]; k < group_start[q + 1]; ++k) f(order[static_cast<std::size_t>(k)]);
  }
  double entry(int col, int row) const {
    const int r = row - lo[static_cast<std::size_t>(col)];
    return (r >= 0 && r < len[static_cast<std::size_t>(col)])
               ? values[static_cast<std::size_t>(col) * static_cast<std::size_t>(window) + static_cast<std::size_t>(r)]
               : 0.0;
  }
};

CosimTrackSetup resolveCosimTrack(const Scene& scene, const SceneTrackOptions& track) {
  if (!scene.has_vehicle)
    throw SceneError(scene.file + ": the co-simulation track needs a vehicle (none in the scene)");
  if (!scene.needsTrackNode())
    throw SceneError(scene.file +
                     ": effects.track_model: rigid runs the vehicle alone; the track side needs "
                     "rigid_fe or flexible");
  CosimTrackSetup setup;
  setup.source = scene.file;
  setup.wheel_count = scene.wheelCount();
  if (setup.wheel_count <= 0) {
    std::ostringstream os;
    os << scene.file << ": vehicle.wheelsets: must be > 0, got " << scene.vehicle.wheelsets;
    throw SceneError(os.str());
  }
  setup.start_arc_length = scene.vehicle.start_arc_length;
  setup.track_step = scene.solver.track_step;
  setup.window = scene.solver.track_window;
  if (scene.runsFeIntegration())
    setup.line = resolveTrackLine(scene, track);
  else
    setup.rigid_geometry = rail::core::buildTrackGeometry(scene);
  // Contact model data, resolved from the scene as the vehicle side resolves them (rail_core's builder).
  setup.wheel_profile = rail::core::wheelProfile(scene);
  setup.rail_profile = rail::core::railProfileCurve(scene);
  setup.nominal_radius = scene.vehicle.nominal_radius;
  setup.contact = rail::core::sceneContact(scene);
  return setup;
}

CosimTrack::CosimTrack(CosimTrackSetup setup, const CosimTrackOptions& options)
    : cost_(options.cost), contact_cost_(options.cost != nullptr ? &options.cost->contact : nullptr) {
  const int n_wheels = setup.wheel_count;
  if (n_wheels <= 0) {
    std::ostringstream os;
    os << setup.source << ": the track needs at least one wheel, got " << n_wheels;
    throw std::invalid_argument(os.str());
  }

  // Geometry (both cases), FE track (flexible only).
  double section_depth = rc::uic60::kCentroidDepth;  // rail section centre below the head top, as the vehicle
  const double rail_height = setup.line ? setup.line->rail_height : 0.0;
  if (setup.line && setup.window.enabled) {
    // Moving window: the setup's window settings, the vehicle's wheel span from the options, first
    // window around the vehicle's start position (leading wheelset at start_arc_length).
    TrackWindowSettings ws = options.window;
    ws.behind = setup.window.behind;
    ws.ahead = setup.window.ahead;
    ws.shift = setup.window.shift;
    ws.length = setup.window.length;
    ws.track_step = setup.track_step;
    ws.include_gravity = options.include_gravity;
    ws.cost = options.cost;
    ws.factor_layout = options.factor_layout;
    if (!(ws.vehicle_length > 0.0) || !std::isfinite(ws.vehicle_length)) {
      std::ostringstream os;
      os << "CosimTrackOptions::window.vehicle_length: the vehicle's wheel span (m, > 0) is needed for the track "
            "window (the vehicle node sends it in the handshake), got "
         << rc::formatNumber(ws.vehicle_length);
      throw std::invalid_argument(os.str());
    }
    const double s_front = setup.start_arc_length;
    auto window = std::make_unique<TrackWindow>(std::move(*setup.line), ws, s_front - ws.vehicle_length, s_front);
    window_ = window.get();
    fe_ = std::move(window);
  } else if (setup.line) {
    // The whole track, from the static equilibrium under its own weight.
    FullLengthTrackSettings fs;
    fs.track_step = setup.track_step;
    fs.include_gravity = options.include_gravity;
    fs.cost = options.cost;
    fs.factor_layout = options.factor_layout;
    auto full = std::make_unique<FullLengthTrack>(std::move(*setup.line), fs);
    full_ = full.get();
    fe_ = std::move(full);
  }
  if (fe_) {
    geometry_ = &fe_->geometry();
    // The contact's section centre on the FE beam axis (the rail centroid node).
    section_depth = rail_height - fe_->data().layout.rail_centroid_height;
  } else {
    if (!setup.rigid_geometry) throw std::invalid_argument(setup.source + ": the track setup has no geometry");
    rigid_geometry_ = std::make_unique<rc::TrackGeometry>(std::move(*setup.rigid_geometry));
    geometry_ = rigid_geometry_.get();
  }

  wheel_profile_ = std::move(setup.wheel_profile);
  rail_profile_ = std::move(setup.rail_profile);
  contact_model_ = std::make_unique<rc::WheelContactModel>(wheel_profile_, setup.nominal_radius, rail_profile_,
                                                           rc::railSectionCentre(rail_profile_, section_depth),
                                                           setup.contact.over(options.contact));
  work_.assign(static_cast<std::size_t>(n_wheels), rc::WheelContactWork());
  result_.assign(static_cast<std::size_t>(n_wheels), rc::WheelContactResult());
  seen_.assign(static_cast<std::size_t>(n_wheels), 0);
  skip_far_searches_ = options.skip_far_searches;
  for (rc::WheelContactWork& w : work_)
    for (rc::DetectionWork& d : w.detection) d.skip_far_searches = skip_far_searches_;

  if (!fe_) return;

  const TrackMesh& mesh = feMesh();
  // Two contacts per wheel, each spread over the 12 DOFs of one rail element.
  loads_ = std::make_unique<NodalLoads>(24 * n_wheels + 1);
  sizeHangingLoads();
  buildRails();
  refreshRails();

  coupling_ = options.coupling;
  if (coupling_ != CosimCoupling::kSemiImplicit) return;
  if (!(options.influence_tolerance > 0.0 && options.influence_tolerance < 1e-3)) {
    std::ostringstream os;
    os << "CosimTrackOptions::influence_tolerance: must be in (0, 1e-3), got " << options.influence_tolerance;
    throw std::runtime_error(os.str());
  }
  for (int r = 0; r < 2; ++r)
    for (std::size_t q = 0; q < mesh.rail_beams[r].size(); ++q)
      if (mesh.rail_beams[r][q] != mesh.rail_beams[r].front() + static_cast<int>(q))
        throw std::runtime_error("CosimTrack: the rail beams of rail " + std::to_string(r) +
                                 " are not numbered consecutively along s (semi-implicit coupling needs it)");
  implicit_ = std::make_unique<Implicit>();
  Implicit& im = *implicit_;
  im.n = static_cast<int>(st().d.size());
  im.tolerance = options.influence_tolerance;
  im.unit.setZero(im.n);
  im.column.setZero(im.n);
  for (Eigen::MatrixXd& columns : im.node_columns) columns.setZero(im.n, kNodeDofs);
  // Window capacity: the widest column of a rail node at mid-track (both rails, 6 DOFs), plus a quarter
  // and two sleeper bays of DOFs for nodes where the track differs.
  int widest = 0;
  for (int r = 0; r < 2; ++r) {
    const int k_mid = static_cast<int>(mesh.rail_nodes[r].size()) / 2;
    for (int j = 0; j < kNodeDofs; ++j) {
      const int g = mesh.dofIndex(mesh.rail_nodes[r][static_cast<std::size_t>(k_mid)], j);
      if (g < 0) continue;
      int lo = 0, len = 0;
      im.window = im.n;  // no clipping while measuring
      solveColumn(g, lo, len);
      widest = std::max(widest, len);
    }
  }
  const int bay_dofs = static_cast<int>(im.n / std::max(1, mesh.n_sleepers));
  im.window = std::min(im.n, widest + widest / 4 + 2 * bay_dofs);
  im.solves = 0;
  im.slots = 4 * n_wheels;
  im.values.assign(static_cast<std::size_t>(im.slots) * kNodeDofs * static_cast<std::size_t>(im.window), 0.0);
  im.lo.assign(static_cast<std::size_t>(im.slots) * kNodeDofs, 0);
  im.len.assign(static_cast<std::size_t>(im.slots) * kNodeDofs, 0);
  im.slot_rail.assign(static_cast<std::size_t>(im.slots), -1);
  im.slot_node.assign(static_cast<std::size_t>(im.slots), -1);
  im.slot_used.assign(static_cast<std::size_t>(im.slots), -1);
  im.pending.reserve(static_cast<std::size_t>(2 * rc::kContactSlots * n_wheels));  // two nodes per link at most
  for (int r = 0; r < 2; ++r) im.node_slot[r].assign(mesh.rail_nodes[r].size(), -1);
  // Up to kContactSlots links per wheel, 3 unknowns each.
  const int max_links = rc::kContactSlots * n_wheels;
  im.links.reserve(static_cast<std::size_t>(max_links));
  im.column_load.assign(static_cast<std::size_t>(im.slots) * kNodeDofs, 0.0);
  im.column_used.assign(static_cast<std::size_t>(im.slots) * kNodeDofs, 0);
  im.used_columns.reserve(static_cast<std::size_t>(im.slots) * kNodeDofs);
  im.memory.assign(static_cast<std::size_t>(rc::kContactSlots * n_wheels), Eigen::Vector3d::Zero());
  im.G.setZero(3 * max_links, 3 * max_links);
  im.S.setZero(3 * max_links, 3 * max_links);
  im.rhs.setZero(3 * max_links);
  im.group_of.assign(static_cast<std::size_t>(max_links), 0);
  im.order.assign(static_cast<std::size_t>(max_links), 0);
  im.group_start.assign(static_cast<std::size_t>(max_links) + 1, 0);
  im.group_index.assign(static_cast<std::size_t>(max_links), 0);
  im.slot_generation.assign(static_cast<std::size_t>(im.slots), 0);
  im.keys = max_links;
  first_dofs_.reserve(static_cast<std::size_t>(max_links) * 4 * kNodeDofs);  // 4 nodes a link (markFirstRows)
  first_candidate_.reserve(first_dofs_.capacity());
  im.pair_blocks.assign(static_cast<std::size_t>(max_links) * static_cast<std::size_t>(max_links),
                        Implicit::PairBlock());
  im.polach = contact_model_->options().polach;
  im.polach.spin = contact_model_->options().spin;
  im.cost = contact_cost_;

  if (options.solve_beside) {
    // The integrators time their right-hand sides and solves into the worker's clock; the loop's thread
    // adds it to cost_ when it takes a result.
    solve_beside_ = true;
    columns_beside_ = options.factor_layout != CholeskyLayout::kSupernodal;
    split_solve_ = options.factor_layout == CholeskyLayout::kSimplicialTwoParts ||
                   options.factor_layout == CholeskyLayout::kBlockedTwoParts;
    if (cost_ != nullptr) {
      cost_->track_solve_beside = true;
      fe_->setCostClock(&worker_cost_);
    }
    worker_ = std::thread([this] { workerLoop(); });
    startBaseSolve(false);
  }
}

CosimTrack::~CosimTrack() {
  if (worker_.joinable()) {
    {
      std::lock_guard<std::mutex> lock(worker_mutex_);
      worker_stop_ = true;
    }
    worker_cv_.notify_all();
    worker_.join();
  }
}

void CosimTrack::solveBase(bool shared) noexcept {
  fillHangingLoads();
  if (!shared || !split_solve_) {
    integ().solveStep(st(), hanging_loads_);
    return;
  }
  NewmarkIntegrator& ig = integ();
  ig.buildRhs(st(), hanging_loads_);
  rail::core::CostClock::Scope timing(cost_ != nullptr ? &worker_cost_ : nullptr, rail::core::CostClock::kTrackSolve);
  solve_stage_.store(1, std::memory_order_release);
  ig.forwardPart(0);
  sharePart(0);
  ig.solveSeparator();
  solve_stage_.store(2, std::memory_order_release);
  if (solve_first_) {
    ig.backwardPart(0, SparseCholesky::Sweep::kFirst);
    sharePart(1);
    first_ready_.store(true, std::memory_order_release);
    solve_stage_.store(3, std::memory_order_release);
    ig.backwardPart(0, SparseCholesky::Sweep::kRest);
    sharePart(2);
    return;
  }
  ig.backwardPart(0);
  sharePart(1);
}

// Solves the second part of a phase (0 forward, 1 backward or its first rows, 2 the backward's other rows)
// if no thread has claimed it yet. True if it did.
bool CosimTrack::claimSecondPart(int phase) noexcept {
  const std::size_t k = static_cast<std::size_t>(phase);
  if (part_claimed_[k].load(std::memory_order_relaxed) || part_claimed_[k].exchange(true, std::memory_order_acq_rel))
    return false;
  NewmarkIntegrator& ig = integ();
  if (phase == 0)
    ig.forwardPart(1);
  else if (phase == 2)
    ig.backwardPart(1, SparseCholesky::Sweep::kRest);
  else if (solve_first_)
    ig.backwardPart(1, SparseCholesky::Sweep::kFirst);
  else
    ig.backwardPart(1);
  part_done_[k].store(true, std::memory_order_release);
  return true;
}

// The worker's side of a phase's second part: solve it unless the loop's thread has claimed it, else wait
// (awake first) until that thread has solved it.
void CosimTrack::sharePart(int phase) noexcept {
  if (claimSecondPart(phase)) return;
  while (!awaitFlag(part_done_[static_cast<std::size_t>(phase)], true, kSolveSpin)) std::this_thread::yield();
}

// The loop's side: solves an open phase's second part if no thread has claimed it yet. True if it did.
bool CosimTrack::helpBaseSolve() noexcept {
  const int stage = solve_stage_.load(std::memory_order_acquire);
  for (int phase = 0; phase < stage; ++phase)
    if (claimSecondPart(phase)) return true;
  return false;
}

const HangingSupports* CosimTrack::hanging() const { return fe_ ? fe_->hanging() : nullptr; }

// The hanging sleepers' loads of the next step from the state at its start (predicted to its end).
void CosimTrack::fillHangingLoads() noexcept {
  hanging_loads_.clear();
  if (const HangingSupports* h = hanging())
    h->addLoads(st().d, st().v, fe_->selfWeightState(), integ().dt(), hanging_loads_);
}

void CosimTrack::sizeHangingLoads() {
  const HangingSupports* h = hanging();
  const int need = h != nullptr ? h->loadCapacity() : 0;
  if (hanging_loads_.capacity() < need) hanging_loads_ = NodalLoads(need);
}

void CosimTrack::workerLoop() noexcept {
  for (;;) {
    // The next job usually follows within a Newton solve: wait awake for a while, then asleep; meanwhile
    // help with the influence columns of a frame's links when the loop's thread posts them.
    auto until = std::chrono::steady_clock::now() + kJobSpin;
    for (int i = 1; !worker_posted_.load(std::memory_order_acquire); ++i) {
      if (columns_posted_.load(std::memory_order_acquire)) {
        helpPendingColumns();
        until = std::chrono::steady_clock::now() + kJobSpin;
        continue;
      }
      __builtin_ia32_pause();
      if (i % 32 == 0 && std::chrono::steady_clock::now() > until) break;
    }
    std::unique_lock<std::mutex> lock(worker_mutex_);
    worker_cv_.wait(lock, [this] { return worker_job_ || worker_stop_ || columns_posted_.load(); });
    if (worker_stop_) return;
    if (!worker_job_) {
      lock.unlock();
      helpPendingColumns();
      continue;
    }
    worker_job_ = false;
    worker_posted_.store(false, std::memory_order_relaxed);
    const bool finish = worker_finish_;
    lock.unlock();
    if (finish) {
      // Timed as the completion (track_rhs, beside the step); awaitCompletion takes the clock.
      if (cost_ != nullptr) integ().setCostClock(&completion_cost_);
      const auto t0 = std::chrono::steady_clock::now();
      const int n = static_cast<int>(st().d.size());
      addColumnLoads(completionSplit(), n);
      integ().completeRows(st(), completionSplit(), n);
      if (cost_ != nullptr) {
        completion_cost_.seconds[rail::core::CostClock::kTrackRhs] +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        integ().setCostClock(&worker_cost_);
      }
      lock.lock();
      worker_completed_ = true;
      worker_completed_flag_.store(true, std::memory_order_release);
      lock.unlock();
      worker_cv_.notify_all();
      // The next right-hand side reads every DOF: wait (awake; the loop's thread is at it) for the other half.
      while (!awaitFlag(lower_completed_, true, kSolveSpin)) std::this_thread::yield();
    }
    solveBase(true);
    lock.lock();
    worker_done_ = true;
    worker_done_flag_.store(true, std::memory_order_release);
    lock.unlock();
    worker_cv_.notify_all();
  }
}

// finish: the worker first completes the Newmark step (the step's column loads, then the completion)
// and says so, then solves the next base step.
void CosimTrack::startBaseSolve(bool finish) noexcept {
  {
    std::lock_guard<std::mutex> lock(worker_mutex_);
    worker_done_ = false;
    worker_done_flag_.store(false, std::memory_order_relaxed);
    worker_completed_ = false;
    worker_completed_flag_.store(false, std::memory_order_relaxed);
    worker_finish_ = finish;
    solve_first_ = split_solve_ && first_marked_;
    first_ready_.store(false, std::memory_order_relaxed);
    lower_completed_.store(false, std::memory_order_relaxed);
    solve_stage_.store(0, std::memory_order_relaxed);
    for (std::size_t k = 0; k < 3; ++k) {
      part_claimed_[k].store(false, std::memory_order_relaxed);
      part_done_[k].store(false, std::memory_order_relaxed);
    }
    worker_job_ = true;
    worker_posted_.store(true, std::memory_order_release);
  }
  worker_cv_.notify_all();
  base_ = BaseSolve::kRunning;
}

// Waits for the worker's share of the step's completion (awake first: it ends about when this thread's
// share does).
void CosimTrack::awaitCompletion() noexcept {
  rail::core::CostClock::Scope timing(cost_, rail::core::CostClock::kTrackSolveWait);
  awaitFlag(worker_completed_flag_, true, kSolveSpin);
  {
    std::unique_lock<std::mutex> lock(worker_mutex_);
    worker_cv_.wait(lock, [this] { return worker_completed_; });
  }
  if (cost_ != nullptr) addClock(completion_cost_, *cost_);
}

void CosimTrack::awaitBaseSolve() noexcept {
  if (base_ != BaseSolve::kRunning) return;
  {
    rail::core::CostClock::Scope timing(cost_, rail::core::CostClock::kTrackSolveWait);
    if (split_solve_)
      awaitHelping(worker_done_flag_);
    else
      awaitFlag(worker_done_flag_, true, kSolveSpin);
    std::unique_lock<std::mutex> lock(worker_mutex_);
    worker_cv_.wait(lock, [this] { return worker_done_; });
  }
  base_ = BaseSolve::kReady;
  takeWorkerCost();
}

// The DOFs of the links' element nodes and of the nodes either side (the next step's links usually lie on
// the same elements or their neighbours), marked in the factor when they differ from the marked ones.
void CosimTrack::markFirstRows() noexcept {
  const Implicit& im = *implicit_;
  const TrackMesh& mesh = feMesh();
  first_candidate_.clear();
  for (const Implicit::Link& L : im.links) {
    const int nodes = static_cast<int>(mesh.rail_nodes[L.rail].size());
    for (int node = std::max(0, L.element - 1); node <= std::min(nodes - 1, L.element + 2); ++node)
      for (int j = 0; j < kNodeDofs; ++j) {
        const int g = mesh.dofIndex(mesh.rail_nodes[L.rail][static_cast<std::size_t>(node)], j);
        if (g >= 0 && first_candidate_.size() < first_candidate_.capacity()) first_candidate_.push_back(g);
      }
  }
  if (first_candidate_.empty() || (first_marked_ && first_candidate_ == first_dofs_)) return;
  first_dofs_.swap(first_candidate_);
  integ().markFirstRows(first_dofs_.data(), static_cast<int>(first_dofs_.size()));
  first_marked_ = true;
}

bool CosimTrack::awaitFirstRows() noexcept {
  if (base_ != BaseSolve::kRunning || !solve_first_ || implicit_->links.empty()) return false;
  for (const Implicit::Link& L : implicit_->links)
    for (const int g : L.dofs)
      if (g >= 0 && !integ().firstCovers(g)) return false;
  rail::core::CostClock::Scope timing(cost_, rail::core::CostClock::kTrackSolveWait);
  if (!awaitHelping(first_ready_)) return false;
  ++first_rows_steps_;
  return true;
}

// Awake until flag is set, taking a part of the base solve when one is open, for kSolveSpin after the last
// part taken. True if the flag was set.
bool CosimTrack::awaitHelping(const std::atomic<bool>& flag) noexcept {
  auto until = std::chrono::steady_clock::now() + kSolveSpin;
  for (int i = 1; !flag.load(std::memory_order_acquire); ++i) {
    if (helpBaseSolve()) {
      until = std::chrono::steady_clock::now() + kSolveSpin;
      continue;
    }
    __builtin_ia32_pause();
    if (i % 32 == 0 && std::chrono::steady_clock::now() > until) return false;
  }
  return true;
}

// Adds the worker's clock to cost_; called while the worker waits for its next job.
void CosimTrack::takeWorkerCost() noexcept {
  if (cost_ != nullptr && solve_beside_) addClock(worker_cost_, *cost_);
}

// The rails as the contact search sees them: the FE rail beams of feMesh(), nodes equally spaced in s. At a
// window move the object is kept and its layout rebuilt in place.
void CosimTrack::buildRails() { buildRailLayout(feMesh(), rail_dofs_, deformation_); }

// After a window move (new mesh and DOF numbering): the rail layout, and the influence columns. A column
// a_g = K_eff^{-1} e_g is keyed by the window-local rail node; a move that reused the matrices and the
// factor (translated copy, straight line) keeps K_eff and the numbering, so every cached column is still
// exact for its local node; a move that refactorised drops them all (they are solved again when a wheel
// needs them). Allocates.
void CosimTrack::onWindowMove() {
  first_marked_ = false;  // another factor, or other DOF numbers
  sizeHangingLoads();
  buildRails();
  rails_current_ = false;
  const int rebuilds = window_->stats().rebuilds;
  if (implicit_ && rebuilds != seen_rebuilds_) {
    Implicit& im = *implicit_;
    std::fill(im.slot_rail.begin(), im.slot_rail.end(), -1);
    std::fill(im.slot_node.begin(), im.slot_node.end(), -1);
    std::fill(im.slot_used.begin(), im.slot_used.end(), -1);
    const TrackMesh& mesh = feMesh();
    for (int r = 0; r < 2; ++r) im.node_slot[r].assign(mesh.rail_nodes[r].size(), -1);
    const int n = static_cast<int>(st().d.size());
    if (n != im.n) {  // a window against a line end may hold other DOFs: resize the scratch
      im.n = n;
      im.unit.setZero(n);
      im.column.setZero(n);
      for (Eigen::MatrixXd& columns : im.node_columns) columns.setZero(n, kNodeDofs);
      if (im.window > n) im.window = n;
    }
    for (long& generation : im.slot_generation) ++generation;
    ++cache_drops_;
  }
  seen_rebuilds_ = rebuilds;
}

int CosimTrack::windowMoves() const { return window_ ? window_->stats().shifts : 0; }
int CosimTrack::windowRebuilds() const { return window_ ? window_->stats().rebuilds : 0; }

int CosimTrack::padForces(double s_from, double s_to, PadForceSample* out, int capacity) const {
  if (!flexible()) return 0;
  rail::core::CostClock::Scope timing(cost_, rail::core::CostClock::kPadForces);
  const TrackMesh& mesh = fe_->mesh();
  if (!pad_probe_ || pad_probe_moves_ != windowMoves()) {
    pad_probe_.reset(new PadForceProbe(mesh));
    pad_probe_moves_ = windowMoves();
  }
  const NewmarkState& s = st();
  return pad_probe_->evaluate(mesh, *geometry_, s.d, s.v, fe_->selfWeightState(), s_from, s_to, out, capacity);
}

int CosimTrack::sleeperCount() const {
  if (!flexible()) return 0;
  return fe_->mesh().n_sleepers;
}

const rc::BeamRailDeformation* CosimTrack::railDeformation() const {
  if (deformation_) refreshRails();
  return deformation_.get();
}

const NewmarkState* CosimTrack::state() const { return fe_ ? &st() : nullptr; }
long CosimTrack::influenceSolves() const { return implicit_ ? implicit_->solves.load() : 0; }
long CosimTrack::influenceClipped() const { return implicit_ ? implicit_->clipped.load() : 0; }
int CosimTrack::influenceWindow() const { return implicit_ ? implicit_->window : 0; }
long CosimTrack::newtonIterations() const { return implicit_ ? implicit_->newton_iterations : 0; }
long CosimTrack::newtonUnconverged() const { return implicit_ ? implicit_->unconverged : 0; }

// Window: the rails carry d = d_g + w (self-weight static state + integrated part).
void CosimTrack::refreshRails() const noexcept {
  if (rails_current_) return;
  fillRailArrays(rail_dofs_, st().d, st().v, fe_->selfWeightState(), 0.0, *deformation_);
  rails_current_ = true;
}

// Rails predicted at t_k = t_{k-1} + h for the contact geometry: d_p = d + h v, v_p = v. (Holding the
// acceleration too gives the same forces; Newmark's accelerations jump after a load step.) With a window
// this is the integrated part w only (d_g is constant within a step).
void CosimTrack::predictRail(int g, double& d_p, double& v_p) const noexcept {
  const NewmarkState& state = st();
  v_p = state.v(g);
  d_p = state.d(g) + fe_->trackStep() * v_p;
}

void CosimTrack::fillPredictedDeformation() noexcept {
  fillRailArrays(rail_dofs_, st().d, st().v, fe_->selfWeightState(), fe_->trackStep(), *deformation_);
  rails_current_ = false;
}

void CosimTrack::writeWrench(int i, const rc::WheelState& ws, const rc::WheelContactResult& res,
                             cc::WrenchFrame& out) const noexcept {
  cc::WheelWrench& w = out.wheels[static_cast<std::size_t>(i)];
  w.f_wheel_in_world = res.wheel_centre.force_in_world;
  w.n_wheel_in_world = ws.R_wheelset_to_world * res.wheel_centre.moment_in_wheelset;
}

// Every wheel's contact on the rails as deformation_ holds them; the FE loads of the active contacts
// (flexible) and the wheel-centre wrenches.
void CosimTrack::evaluateContacts(const cc::WheelStateFrame& states, cc::WrenchFrame& out) noexcept {
  const int n = wheelCount();
  const bool fe = fe_ != nullptr;
  if (fe) loads_->clear();
  for (int i = 0; i < n; ++i) {
    const rc::WheelState& ws = states.wheels[static_cast<std::size_t>(i)];
    const std::size_t id = ws.id;
    const rc::RailSide side = (ws.id % 2 == 0) ? rc::RailSide::kLeft : rc::RailSide::kRight;
    rc::WheelContactResult& res = result_[id];
    if (fe) {
      contact_model_->evaluate(ws, side, *geometry_, *deformation_, work_[id], res, contact_cost_);
      const int rail = side == rc::RailSide::kLeft ? kLeftRail : kRightRail;
      // The semi-implicit coupling loads the rails through the influence columns (applyLinkForces).
      for (int c = 0; c < rc::kContactSlots && coupling_ == CosimCoupling::kExplicit; ++c) {
        const rc::ContactPointResult& cp = res.contact[c];
        if (!cp.active) continue;
        // Eq. 15 for this contact about its own section centre, then eq. 16 onto the element's nodes.
        addRailPointLoad(feMesh(), rail, cp.s_r, cp.rail_wrench.force_in_world, cp.rail_wrench.moment_in_world,
                         *loads_);
      }
    } else {
      contact_model_->evaluate(ws, side, *geometry_, rc::RigidRailDeformation(), work_[id], res, contact_cost_);
    }
    out.wheels[static_cast<std::size_t>(i)].id = ws.id;
    writeWrench(i, ws, res, out);
  }
}

void CosimTrack::setExactGaps(bool exact) noexcept {
  if (exact == exact_gaps_) return;
  exact_gaps_ = exact;
  for (rc::WheelContactWork& w : work_)
    for (rc::DetectionWork& d : w.detection) d.skip_far_searches = skip_far_searches_ && !exact;
}

CosimStepStatus CosimTrack::step(const cc::WheelStateFrame& states, cc::WrenchFrame& out) noexcept {
  const CosimStepStatus status = stepForces(states, out);
  if (status == CosimStepStatus::kOk) finishStep();
  return status;
}

CosimStepStatus CosimTrack::stepForces(const cc::WheelStateFrame& states, cc::WrenchFrame& out) noexcept {
  finishStep();  // the previous step's, if its caller did not
  const int n = wheelCount();
  if (static_cast<int>(states.count) != n || states.capacity() < n || out.capacity() < n)
    return CosimStepStatus::kWrongWheelCount;
  for (int i = 0; i < n; ++i) seen_[static_cast<std::size_t>(i)] = 0;
  for (int i = 0; i < n; ++i) {
    const std::uint32_t id = states.wheels[static_cast<std::size_t>(i)].id;
    if (id >= static_cast<std::uint32_t>(n) || seen_[id]) return CosimStepStatus::kBadWheelId;
    seen_[id] = 1;
  }
  if (window_) {
    // The window follows the wheels; a move allocates (and is timed); every wheel must then be on it.
    double s_min = std::numeric_limits<double>::infinity(), s_max = -s_min;
    for (int i = 0; i < n; ++i) {
      const double s = states.wheels[static_cast<std::size_t>(i)].arc_length;
      if (!std::isfinite(s)) return CosimStepStatus::kWheelOutsideWindow;
      s_min = std::min(s_min, s);
      s_max = std::max(s_max, s);
    }
    try {
      const auto t0 = std::chrono::steady_clock::now();
      if (!window_->holds(s_min, s_max)) awaitBaseSolve();  // a move changes what the base solve reads
      if (window_->follow(s_min, s_max)) {
        base_ = BaseSolve::kNone;  // solved on the old window
        onWindowMove();
        const double move_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        window_move_s_ += move_s;
        if (cost_ != nullptr) cost_->add(rail::core::CostClock::kWindowMoves, move_s);
      }
    } catch (const std::exception&) {
      return CosimStepStatus::kWindowMoveFailed;
    }
    if (!window_->covers(s_min, s_max)) return CosimStepStatus::kWheelOutsideWindow;
  }
  out.count = static_cast<std::uint32_t>(n);
  out.step = states.step;
  out.time = states.time;
  out.scene_hash = states.scene_hash;

  const bool integrate = fe_ && states.step > 0;
  // The rails the contact sees: t_{k-1} (explicit, and step 0) or predicted at t_k.
  if (integrate && coupling_ != CosimCoupling::kExplicit)
    fillPredictedDeformation();
  else if (deformation_)
    refreshRails();
  evaluateContacts(states, out);

  if (integrate && coupling_ == CosimCoupling::kSemiImplicit) {
    implicitCorrection(states, out);
  }
  ++frames_;
  finish_ = integrate ? Finish::kIntegrate : Finish::kFrameOnly;
  return CosimStepStatus::kOk;
}

void CosimTrack::finishStep() noexcept {
  if (finish_ == Finish::kNone) return;
  const bool integrate = finish_ == Finish::kIntegrate;
  finish_ = Finish::kNone;
  if (integrate) {
    switch (coupling_) {
      case CosimCoupling::kExplicit:
        fillHangingLoads();
        integ().step(st(), *loads_, &hanging_loads_);
        break;
      case CosimCoupling::kSemiImplicit:
        if (solve_beside_) {
          if (base_ == BaseSolve::kRunning) {  // the Newton started on the first rows: the rest of the pass
            awaitBaseSolve();
            base_ = BaseSolve::kNone;
          }
          if (split_solve_) markFirstRows();
          // Both threads complete this step, half of the DOFs each; the worker then solves the next base step.
          startBaseSolve(true);
          const auto t0 = std::chrono::steady_clock::now();
          addColumnLoads(0, completionSplit());
          integ().completeRows(st(), 0, completionSplit());
          lower_completed_.store(true, std::memory_order_release);
          const double lower_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
          awaitCompletion();
          integ().advanceTime(st());
          clearColumnLoads();
          if (cost_ != nullptr) {  // the completion: one call of track_rhs, as completeStep()
            cost_->seconds[rail::core::CostClock::kTrackRhs] += lower_s;
            ++cost_->calls[rail::core::CostClock::kTrackRhs];
          }
        } else {
          const int n = static_cast<int>(st().d.size());
          addColumnLoads(0, n);
          clearColumnLoads();
          integ().completeStep(st());
        }
        break;
    }
    fe_->finishStep();  // a window's own rail arrays and step count
    ++newmark_steps_;
    rails_current_ = false;  // filled when next read (railDeformation(), the explicit contact)
  }
  if (solve_beside_ && base_ == BaseSolve::kNone) startBaseSolve(false);
}

// x = K_eff^{-1} e_dof into im.column and its window (trimColumn).
void CosimTrack::solveColumn(int dof, int& lo, int& len) noexcept {
  Implicit& im = *implicit_;
  im.unit(dof) = 1.0;
  integ().solveEffective(im.unit, im.column);
  im.unit(dof) = 0.0;
  ++im.solves;
  trimColumn(dof, im.column.data(), lo, len);
}

// The window [lo, lo + len) of column x of dof where |x| > tolerance * max |x|, cut to the capacity around
// dof if wider.
void CosimTrack::trimColumn(int dof, const double* x, int& lo, int& len) noexcept {
  Implicit& im = *implicit_;
  const double cut = im.tolerance * Eigen::Map<const Eigen::VectorXd>(x, im.n).cwiseAbs().maxCoeff();
  int first = 0, last = im.n - 1;
  while (first < dof && std::abs(x[first]) <= cut) ++first;
  while (last > dof && std::abs(x[last]) <= cut) --last;
  len = last - first + 1;
  lo = first;
  if (len > im.window) {
    ++im.clipped;
    lo = std::min(std::max(0, dof - im.window / 2), im.n - im.window);
    len = im.window;
  }
}

// Gives rail node (rail, node) a slot for its influence columns unless it has one; a slot newly given is
// queued for solvePendingColumns.
void CosimTrack::claimNodeColumns(int rail, int node) noexcept {
  Implicit& im = *implicit_;
  int& cached = im.node_slot[rail][static_cast<std::size_t>(node)];
  if (cached >= 0) {
    im.slot_used[static_cast<std::size_t>(cached)] = frames_;
    return;
  }
  int slot = 0;
  for (int s = 1; s < im.slots; ++s)
    if (im.slot_used[static_cast<std::size_t>(s)] < im.slot_used[static_cast<std::size_t>(slot)]) slot = s;
  if (im.slot_rail[static_cast<std::size_t>(slot)] >= 0)
    im.node_slot[im.slot_rail[static_cast<std::size_t>(slot)]]
                [static_cast<std::size_t>(im.slot_node[static_cast<std::size_t>(slot)])] = -1;
  im.slot_rail[static_cast<std::size_t>(slot)] = rail;
  im.slot_node[static_cast<std::size_t>(slot)] = node;
  im.slot_used[static_cast<std::size_t>(slot)] = frames_;
  cached = slot;
  ++im.slot_generation[static_cast<std::size_t>(slot)];
  im.pending.push_back(slot);
}

// Solves the influence columns of the node of slot (its free DOFs in one pass over the factor) with the
// factor's column workspace `lane`, into the slot.
void CosimTrack::solveSlotColumns(int slot, int lane) noexcept {
  Implicit& im = *implicit_;
  const int rail = im.slot_rail[static_cast<std::size_t>(slot)];
  const int node = im.slot_node[static_cast<std::size_t>(slot)];
  const TrackMesh& mesh = feMesh();
  const int mesh_node = mesh.rail_nodes[rail][static_cast<std::size_t>(node)];
  // The node's free DOFs solved together (one pass over the factor).
  std::array<int, kNodeDofs> dofs{}, which{};
  int count = 0;
  for (int j = 0; j < kNodeDofs; ++j) {
    const std::size_t col = static_cast<std::size_t>(slot) * kNodeDofs + static_cast<std::size_t>(j);
    const int g = mesh.dofIndex(mesh_node, j);
    im.lo[col] = 0;
    im.len[col] = 0;
    if (g < 0) continue;
    dofs[static_cast<std::size_t>(count)] = g;
    which[static_cast<std::size_t>(count)] = j;
    ++count;
  }
  if (count == 0) return;
  Eigen::MatrixXd& columns = im.node_columns[static_cast<std::size_t>(lane)];
  integ().solveEffectiveColumns(dofs.data(), count, columns, lane);
  im.solves.fetch_add(count, std::memory_order_relaxed);
  for (int c = 0; c < count; ++c) {
    const std::size_t col = static_cast<std::size_t>(slot) * kNodeDofs + static_cast<std::size_t>(which[c]);
    const double* x = columns.col(c).data();
    trimColumn(dofs[static_cast<std::size_t>(c)], x, im.lo[col], im.len[col]);
    std::copy(x + im.lo[col], x + im.lo[col] + im.len[col],
              im.values.begin() + static_cast<std::ptrdiff_t>(col * static_cast<std::size_t>(im.window)));
  }
}

// The columns of the slots claimed this frame. With the worker beside and more than one slot, both threads
// take slots in turn (the worker once its base solve is done): the same solves, in other hands.
void CosimTrack::solvePendingColumns() noexcept {
  Implicit& im = *implicit_;
  const int count = static_cast<int>(im.pending.size());
  if (count == 0) return;
  if (!solve_beside_ || !columns_beside_ || count < 2) {
    for (const int slot : im.pending) solveSlotColumns(slot, 0);
    im.pending.clear();
    return;
  }
  column_next_.store(0, std::memory_order_relaxed);
  column_done_.store(0, std::memory_order_relaxed);
  {
    std::lock_guard<std::mutex> lock(worker_mutex_);
    columns_posted_.store(true);
  }
  worker_cv_.notify_all();
  for (int i; (i = column_next_.fetch_add(1)) < count;) {
    solveSlotColumns(im.pending[static_cast<std::size_t>(i)], 0);
    column_done_.fetch_add(1);
  }
  // A slot the worker took is at most one node's columns away.
  while (column_done_.load() < count) __builtin_ia32_pause();
  columns_posted_.store(false);
  while (worker_in_columns_.load()) __builtin_ia32_pause();
  im.pending.clear();
}

void CosimTrack::helpPendingColumns() noexcept {
  worker_in_columns_.store(true);
  if (columns_posted_.load()) {
    Implicit& im = *implicit_;
    const int count = static_cast<int>(im.pending.size());
    while (column_next_.load(std::memory_order_relaxed) < count) {
      const int i = column_next_.fetch_add(1);
      if (i >= count) break;
      solveSlotColumns(im.pending[static_cast<std::size_t>(i)], 1);
      column_done_.fetch_add(1);
    }
  }
  worker_in_columns_.store(false);
}

// The contact law of link L with the rail contact point displaced by u (world) from the start of the step
// and moving at u_dot = (2/h) u - base_dot (Newmark), everything else frozen at the predicted state:
// the same sequence as WheelContactModel::evaluate (eq. 9, creepages, Kalker, Polach, eq. 12).
void CosimTrack::Implicit::law(const rc::WheelContactModel& model, double h, const Link& L, const Eigen::Vector3d& u,
                               LawOut& o) const noexcept {
  const rc::WheelContactOptions& opt = model.options();
  const Eigen::Vector3d& n = L.R_contact_to_world.col(2);
  const Eigen::Vector3d& t_w = L.R_contact_to_world.col(0);
  const Eigen::Vector3d dv_rail = (2.0 / h) * u - L.base_dot;
  const Eigen::Vector3d v_rail = L.v_rail_p + dv_rail;
  o = LawOut();
  o.delta = L.delta_p + n.dot(u - L.u_p);
  o.delta_dot = -(L.v_wheel - v_rail).dot(n);
  o.N = rc::dampedNormalForce(L.K, o.delta, o.delta_dot, L.v_impact, opt.damping);
  if (!(o.N > 0.0)) return;
  const double cbrt_N = std::cbrt(o.N);
  o.a = L.a_coeff * cbrt_N;
  o.b = L.b_coeff * cbrt_N;
  const rc::Creepages cr = rc::computeCreepages(L.v_wheel, v_rail, L.omega_wheel, L.omega_rail_p, L.R_contact_to_world,
                                                L.V_p - dv_rail.dot(t_w), opt.creepage);
  o.nu_x = cr.nu_x;
  o.nu_y = cr.nu_y;
  o.phi = opt.spin ? cr.phi : 0.0;
  if (o.a > 0.0 && o.b > 0.0) {
    rc::PolachInput pin;
    pin.nu_x = o.nu_x;
    pin.nu_y = o.nu_y;
    pin.phi = o.phi;
    pin.N = o.N;
    pin.a = o.a;
    pin.b = o.b;
    pin.G = model.shearModulus();
    pin.mu0 = opt.friction;
    pin.V = cr.V_ref;
    pin.c = L.kalker;
    const rc::PolachResult pr = rc::polachForces(pin, polach);
    o.F_long = pr.Fx;
    o.F_lat = pr.Fy;
    if (cost != nullptr) {
      ++cost->creep_evaluations;
      if (polach.spin) ++cost->spin_evaluations;  // polachForces evaluated its spin terms
    }
  }
  o.F_wheel = rc::contactForceInWorld(L.R_contact_to_world, o.F_long, o.F_lat, o.N);
}

// Semi-implicit coupling, after the load-free solve x_b = K_eff^{-1} rhs (rhs: Newmark's right-hand side and
// the self-weight, without contact loads). Each contact c in contact at the predicted state keeps its
// geometry and gets its force from the contact law along the rail motion of t_k, to first order in the
// rail contact point's displacement
//   u_c = W_c' d  (W_c: nodal loads of unit world forces at the point, eq. 16),
//   u_dot_c = W_c' v,  v = (2/h) (d - d_{k-1}) - v_{k-1}  (Newmark).
// Its rail load W_c f_c makes d = x_b + sum_e K_eff^{-1} W_e f_e, so
//   u_c = u0_c + sum_e G_ce (f_e - f_p,e),  u0_c = W_c' x_b + sum_e G_ce f_p,e,  G_ce = W_c' K_eff^{-1} W_e
// (cached influence columns; u0 is where the forces of the prediction f_p put the point), and the rail
// forces f solve f_c + F_wheel,c(u_c(f)) = 0 by Newton (3 unknowns per contact, law Jacobian by
// differences). The contact results and the wheel wrenches take the final forces; d takes them in
// finishStep.
void CosimTrack::implicitCorrection(const cc::WheelStateFrame& states, cc::WrenchFrame& out) noexcept {
  // The links and G do not read the base solve: with the simplicial factor (its own scratch for the
  // columns) they are built while the base solve may still run beside.
  if (columns_beside_) {
    ForcesTime timing(contact_cost_);
    gatherLinks(states);
    buildInfluence();
  }
  if (!(columns_beside_ && awaitFirstRows())) {
    awaitBaseSolve();
    if (base_ != BaseSolve::kReady) solveBase();
    base_ = BaseSolve::kNone;
  }
  ForcesTime timing(contact_cost_);
  if (!columns_beside_) {
    gatherLinks(states);
    buildInfluence();
  }
  if (implicit_->links.empty()) return;
  baseDisplacement();
  solveLinkForces();
  applyLinkForces(states, out);
}

// The links: every contact in contact at the predicted state, its element, load map W, frozen law data,
// and W' x_b; the influence columns of its element's nodes cached.
void CosimTrack::gatherLinks(const cc::WheelStateFrame& states) noexcept {
  Implicit& im = *implicit_;
  const TrackMesh& mesh = feMesh();
  const NewmarkState& state = st();
  const double h = integ().dt();
  const rc::NormalDampingParams& damping = contact_model_->options().damping;
  im.links.clear();
  const int n = wheelCount();
  for (int i = 0; i < n; ++i) {
    const cc::WheelState& in = states.wheels[static_cast<std::size_t>(i)];
    const rc::WheelContactResult& res = result_[in.id];
    const int rail = in.id % 2 == 0 ? kLeftRail : kRightRail;
    const rc::RailSide side = rail == kLeftRail ? rc::RailSide::kLeft : rc::RailSide::kRight;
    for (int c = 0; c < rc::kContactSlots; ++c) {
      const rc::ContactPointResult& cp = res.contact[c];
      if (!cp.active || !(cp.penetration > 0.0)) continue;
      Eigen::Vector3d& memory = im.memory[static_cast<std::size_t>(rc::kContactSlots * in.id + c)];
      const double v_impact = work_[in.id].impact[c].impact_velocity;
      // Eq. 9's K and the Hertz semi-axis coefficients: from this evaluation when N > 0, else the last seen.
      const double D = 0.75 * (1.0 - damping.restitution * damping.restitution) /
                       std::max(std::abs(v_impact), damping.impact_velocity_floor);
      const double factor = 1.0 + D * cp.penetration_rate;
      if (cp.N > 0.0 && factor > 0.0 && cp.a > 0.0 && cp.b > 0.0) {
        const double cbrt_N = std::cbrt(cp.N);
        memory =
            Eigen::Vector3d(cp.N / (std::pow(cp.penetration, damping.exponent) * factor), cp.a / cbrt_N, cp.b / cbrt_N);
      }
      if (!(memory(0) > 0.0)) continue;
      int beam = 0;
      double xi = 0.0;
      if (!mesh.locateRail(rail, cp.s_r, beam, xi)) continue;
      Implicit::Link L;
      L.frame_index = i;
      L.wheel = static_cast<int>(in.id);
      L.contact = c;
      L.rail = rail;
      L.element = beam - mesh.rail_beams[rail].front();
      const BeamElement& b = mesh.beams[static_cast<std::size_t>(beam)];
      for (int j = 0; j < kNodeDofs; ++j) {
        L.dofs[static_cast<std::size_t>(j)] = mesh.dofIndex(b.node_i, j);
        L.dofs[static_cast<std::size_t>(kNodeDofs + j)] = mesh.dofIndex(b.node_j, j);
      }
      const Eigen::Vector3d arm = cp.p_rail_in_world - cp.p_section_centre_in_world;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d e = Eigen::Vector3d::Unit(k);
        L.W.col(k) = rc::beamEquivalentNodalLoadsWorld(xi, b.length, b.R_local_to_world, e, arm.cross(e));
      }
      L.R_contact_to_world = cp.R_contact_to_world;
      L.v_wheel = in.v_wheel_in_world + in.omega_wheelset_in_world.cross(cp.p_wheel_in_world - in.p_wheel_in_world);
      rc::RailSectionMotion motion;
      deformation_->sectionMotion(side, cp.s_r, motion);
      L.v_rail_p = motion.u_dot + motion.theta_dot.cross(arm);
      L.omega_wheel = in.omega_wheelset_in_world;
      L.omega_rail_p = motion.theta_dot;
      L.V_p = (in.v_wheel_in_world - motion.u_dot).dot(cp.R_contact_to_world.col(0));
      L.K = memory(0);
      L.a_coeff = memory(1);
      L.b_coeff = memory(2);
      L.kalker = rc::KalkerTable::builtin().evaluate(L.a_coeff / L.b_coeff, contact_model_->poissonRatio());
      L.v_impact = v_impact;
      L.delta_p = cp.penetration;
      L.u_p.setZero();
      L.u0.setZero();
      L.base_dot.setZero();
      for (int j = 0; j < 12; ++j) {
        const int g = L.dofs[static_cast<std::size_t>(j)];
        if (g < 0) continue;
        double d_p = 0.0, v_p = 0.0;
        predictRail(g, d_p, v_p);
        L.u_p += L.W.row(j).transpose() * d_p;
        L.base_dot += L.W.row(j).transpose() * ((2.0 / h) * state.d(g) + state.v(g) + v_p);
      }
      L.f_p = -cp.force_on_wheel_in_world;
      L.f = L.f_p;
      claimNodeColumns(rail, L.element);
      claimNodeColumns(rail, L.element + 1);
      im.links.push_back(L);
    }
  }
  solvePendingColumns();
}

// K_eff^{-1} between the element DOFs of Lc (rows) and of Le (columns), from Le's influence columns, or as
// read in an earlier step for the same elements and the same columns.
const std::array<double, 144>& CosimTrack::Implicit::pairBlock(const Link& Lc, const Link& Le) noexcept {
  Implicit& im = *this;
  const int slot_0 = im.node_slot[Le.rail][static_cast<std::size_t>(Le.element)];  // Le's two nodes
  const int slot_1 = im.node_slot[Le.rail][static_cast<std::size_t>(Le.element) + 1];
  const long generation_0 = im.slot_generation[static_cast<std::size_t>(slot_0)];
  const long generation_1 = im.slot_generation[static_cast<std::size_t>(slot_1)];
  const int key_c = rc::kContactSlots * Lc.wheel + Lc.contact, key_e = rc::kContactSlots * Le.wheel + Le.contact;
  Implicit::PairBlock& p = im.pair_blocks[static_cast<std::size_t>(key_c) * static_cast<std::size_t>(im.keys) +
                                          static_cast<std::size_t>(key_e)];
  if (p.rail_c == Lc.rail && p.element_c == Lc.element && p.slot_0 == slot_0 && p.slot_1 == slot_1 &&
      p.generation_0 == generation_0 && p.generation_1 == generation_1)
    return p.a;
  for (int j = 0; j < 12; ++j) {
    const int col = (j < kNodeDofs ? slot_0 : slot_1) * kNodeDofs + j % kNodeDofs;
    for (int i = 0; i < 12; ++i) {
      const int row = Lc.dofs[static_cast<std::size_t>(i)];
      p.a[static_cast<std::size_t>(12 * j + i)] = row >= 0 ? im.entry(col, row) : 0.0;
    }
  }
  p.rail_c = Lc.rail;
  p.element_c = Lc.element;
  p.slot_0 = slot_0;
  p.slot_1 = slot_1;
  p.generation_0 = generation_0;
  p.generation_1 = generation_1;
  return p.a;
}

// G = W' K_eff^{-1} W from the influence columns (3 x 3 blocks).
void CosimTrack::buildInfluence() noexcept {
  Implicit& im = *implicit_;
  const int m = static_cast<int>(im.links.size());
  for (int c = 0; c < m; ++c) im.group_of[static_cast<std::size_t>(c)] = c;
  auto root = [&im](int c) {
    while (im.group_of[static_cast<std::size_t>(c)] != c) c = im.group_of[static_cast<std::size_t>(c)];
    return c;
  };
  for (int e = 0; e < m; ++e) {
    const Implicit::Link& Le = im.links[static_cast<std::size_t>(e)];
    // The DOF range Le's columns reach (their entries beyond it are zero).
    int reach_lo = im.n, reach_hi = 0;
    for (int j = 0; j < 12; ++j) {
      const int col =
          im.node_slot[Le.rail][static_cast<std::size_t>(Le.element + j / kNodeDofs)] * kNodeDofs + j % kNodeDofs;
      if (im.len[static_cast<std::size_t>(col)] == 0) continue;
      reach_lo = std::min(reach_lo, im.lo[static_cast<std::size_t>(col)]);
      reach_hi = std::max(reach_hi, im.lo[static_cast<std::size_t>(col)] + im.len[static_cast<std::size_t>(col)]);
    }
    for (int c = 0; c < m; ++c) {
      const Implicit::Link& Lc = im.links[static_cast<std::size_t>(c)];
      bool reached = false;
      for (int i = 0; i < 12 && !reached; ++i) {
        const int g = Lc.dofs[static_cast<std::size_t>(i)];
        reached = g >= reach_lo && g < reach_hi;
      }
      if (!reached) {
        im.G.block<3, 3>(3 * c, 3 * e).setZero();
        continue;
      }
      const int root_c = root(c), root_e = root(e);
      if (root_c != root_e) im.group_of[static_cast<std::size_t>(std::max(root_c, root_e))] = std::min(root_c, root_e);
      const std::array<double, 144>& a = im.pairBlock(Lc, Le);
      Eigen::Matrix3d g = Eigen::Matrix3d::Zero();
      for (int j = 0; j < 12; ++j) {
        Eigen::Vector3d a_w = Eigen::Vector3d::Zero();  // W_c' K_eff^{-1} e_j
        for (int i = 0; i < 12; ++i)
          if (Lc.dofs[static_cast<std::size_t>(i)] >= 0)
            a_w += Lc.W.row(i).transpose() * a[static_cast<std::size_t>(12 * j + i)];
        g += a_w * Le.W.row(j);
      }
      im.G.block<3, 3>(3 * c, 3 * e) = g;
    }
  }
  // Groups in order of their first link, links ascending within each.
  int groups = 0, placed = 0;
  for (int c = 0; c < m; ++c) im.group_of[static_cast<std::size_t>(c)] = root(c);
  for (int c = 0; c < m; ++c) {
    if (im.group_of[static_cast<std::size_t>(c)] != c) continue;
    im.group_start[static_cast<std::size_t>(groups++)] = placed;
    for (int d = c; d < m; ++d)
      if (im.group_of[static_cast<std::size_t>(d)] == c) im.order[static_cast<std::size_t>(placed++)] = d;
  }
  im.group_start[static_cast<std::size_t>(groups)] = placed;
  im.groups = groups;
  for (int q = 0; q < groups; ++q)
    for (int k = im.group_start[static_cast<std::size_t>(q)]; k < im.group_start[static_cast<std::size_t>(q) + 1]; ++k)
      im.group_index[static_cast<std::size_t>(im.order[static_cast<std::size_t>(k)])] = q;
}

// u0 = W' x_b + G f_p: each contact point's displacement under the base solve and the prediction's forces.
void CosimTrack::baseDisplacement() noexcept {
  Implicit& im = *implicit_;
  const Eigen::VectorXd& x_base = integ().stepDisplacement();
  const int m = static_cast<int>(im.links.size());
  for (int c = 0; c < m; ++c) {
    Implicit::Link& Lc = im.links[static_cast<std::size_t>(c)];
    Lc.u0.setZero();
    for (int j = 0; j < 12; ++j) {
      const int g = Lc.dofs[static_cast<std::size_t>(j)];
      if (g >= 0) Lc.u0 += Lc.W.row(j).transpose() * x_base(g);
    }
    im.forGroupOf(c,
                  [&](int e) { Lc.u0 += im.G.block<3, 3>(3 * c, 3 * e) * im.links[static_cast<std::size_t>(e)].f_p; });
  }
}

// Newton on the rail contact-point displacements u (3 per contact):
//   r_c(u) = u_c - u0_c - sum_e G_ce (f_e(u_e) - f_p,e) = 0,  f_e(u_e) = -F_wheel,e(u_e),
// Jacobian I + G J (J_e = d F_wheel,e / d u_e by differences), with a backtracking line search on |r|^2:
// the creep law saturates within micrometres of slip at low speed, where undamped steps overshoot.
void CosimTrack::solveLinkForces() noexcept {
  Implicit& im = *implicit_;
  const double h = integ().dt();
  const int m = static_cast<int>(im.links.size());
  constexpr int kMaxIterations = 40;
  constexpr double kDu = 1e-11;  // m, difference step of the law Jacobian (rail velocity step 2 kDu / h)
  bool converged = false;
  Implicit::LawOut lp;
  // known: F_wheel already holds the law at u (the line search's accepted trial): only the Jacobian is new.
  auto residuals = [&](bool jacobian, bool known = false) {
    double merit = 0.0;
    for (int c = 0; c < m; ++c) {
      Implicit::Link& Lc = im.links[static_cast<std::size_t>(c)];
      if (!known) {
        im.law(*contact_model_, h, Lc, Lc.u, Lc.at_u);
        Lc.F_wheel = Lc.at_u.F_wheel;
      }
      if (jacobian)
        for (int k = 0; k < 3; ++k) {
          im.law(*contact_model_, h, Lc, Lc.u + kDu * Eigen::Vector3d::Unit(k), lp);
          Lc.J.col(k) = (lp.F_wheel - Lc.F_wheel) / kDu;
        }
    }
    for (int c = 0; c < m; ++c) {
      Implicit::Link& Lc = im.links[static_cast<std::size_t>(c)];
      Lc.R = Lc.u - Lc.u0;
      im.forGroupOf(c, [&](int e) {
        const Implicit::Link& Le = im.links[static_cast<std::size_t>(e)];
        Lc.R += im.G.block<3, 3>(3 * c, 3 * e) * (Le.F_wheel + Le.f_p);
      });
      merit += Lc.R.squaredNorm();
    }
    return merit;
  };
  for (int c = 0; c < m; ++c) im.links[static_cast<std::size_t>(c)].u = im.links[static_cast<std::size_t>(c)].u0;
  double merit = residuals(true);
  for (int it = 0; it < kMaxIterations; ++it) {
    ++im.newton_iterations;
    // Converged when every contact point is within 1e-12 m of where its force puts it (rail velocity
    // error 2e-12 / h) and the force mismatch J r is below 1e-9 of its force (+ 1 N).
    bool done = true;
    for (int c = 0; c < m; ++c) {
      const Implicit::Link& Lc = im.links[static_cast<std::size_t>(c)];
      done = done && Lc.R.norm() <= 1e-12 && (Lc.J * Lc.R).norm() <= 1e-9 * (1.0 + Lc.F_wheel.norm());
    }
    if (done) {
      converged = true;
      break;
    }
    // (I + G J) du = -r, dense LU with partial pivoting, group by group (the blocks between groups are
    // zero: the same arithmetic as on the whole matrix).
    for (int q = 0; q < im.groups; ++q) {
      const int* idx = im.order.data() + im.group_start[static_cast<std::size_t>(q)];
      const int mq = im.group_start[static_cast<std::size_t>(q) + 1] - im.group_start[static_cast<std::size_t>(q)];
      const int N3 = 3 * mq;
      for (int a = 0; a < mq; ++a) {
        for (int b = 0; b < mq; ++b)
          im.S.block<3, 3>(3 * a, 3 * b).noalias() =
              im.G.block<3, 3>(3 * idx[a], 3 * idx[b]) * im.links[static_cast<std::size_t>(idx[b])].J;
        im.S.block<3, 3>(3 * a, 3 * a) += Eigen::Matrix3d::Identity();
        im.rhs.segment<3>(3 * a) = -im.links[static_cast<std::size_t>(idx[a])].R;
      }
      for (int k = 0; k < N3; ++k) {
        int p = k;
        for (int i = k + 1; i < N3; ++i)
          if (std::abs(im.S(i, k)) > std::abs(im.S(p, k))) p = i;
        if (p != k) {
          for (int j = 0; j < N3; ++j) std::swap(im.S(k, j), im.S(p, j));
          std::swap(im.rhs(k), im.rhs(p));
        }
        const double piv = im.S(k, k);
        for (int i = k + 1; i < N3; ++i) {
          const double l = im.S(i, k) / piv;
          if (l == 0.0) continue;
          for (int j = k + 1; j < N3; ++j) im.S(i, j) -= l * im.S(k, j);
          im.rhs(i) -= l * im.rhs(k);
        }
      }
      for (int k = N3 - 1; k >= 0; --k) {
        double v = im.rhs(k);
        for (int j = k + 1; j < N3; ++j) v -= im.S(k, j) * im.rhs(j);
        im.rhs(k) = v / im.S(k, k);
      }
      for (int a = 0; a < mq; ++a) im.links[static_cast<std::size_t>(idx[a])].du = im.rhs.segment<3>(3 * a);
    }
    for (int c = 0; c < m; ++c) {
      Implicit::Link& Lc = im.links[static_cast<std::size_t>(c)];
      Lc.u_start = Lc.u;
    }
    double alpha = 1.0, trial = 0.0;
    for (int halving = 0; halving < 40; ++halving) {
      for (int c = 0; c < m; ++c) {
        Implicit::Link& Lc = im.links[static_cast<std::size_t>(c)];
        Lc.u = Lc.u_start + alpha * Lc.du;
      }
      trial = residuals(false);
      if (trial <= (1.0 - 1e-4 * alpha) * merit) break;
      alpha *= 0.5;
    }
    merit = residuals(true, true);  // u is the last trial's
  }
  if (!converged) ++im.unconverged;
  for (int c = 0; c < m; ++c) {
    Implicit::Link& Lc = im.links[static_cast<std::size_t>(c)];
    Lc.f = -Lc.F_wheel;
  }
}

// The contact results with the final forces, the wheel-centre wrenches (eq. 13) and the rail-section
// resultant (eq. 15) of the wheels concerned; the nodal loads W f summed per influence column for
// addColumnLoads (finishStep).
void CosimTrack::applyLinkForces(const cc::WheelStateFrame& states, cc::WrenchFrame& out) noexcept {
  Implicit& im = *implicit_;
  const int m = static_cast<int>(im.links.size());
  for (int c = 0; c < m; ++c) {
    Implicit::Link& Lc = im.links[static_cast<std::size_t>(c)];
    const Implicit::LawOut& lo = Lc.at_u;  // Newton's last evaluation, at the final u
    rc::ContactPointResult& cp = result_[static_cast<std::size_t>(Lc.wheel)].contact[Lc.contact];
    cp.N = lo.N;
    cp.F_long = lo.F_long;
    cp.F_lat = lo.F_lat;
    cp.a = lo.a;
    cp.b = lo.b;
    cp.nu_x = lo.nu_x;
    cp.nu_y = lo.nu_y;
    cp.phi = lo.phi;
    cp.penetration = lo.delta;
    cp.penetration_rate = lo.delta_dot;
    cp.force_on_wheel_in_world = lo.F_wheel;  // = -f, the force the rails carry
    cp.rail_wrench = rc::railSectionWrench(Lc.f, Eigen::Vector3d::Zero(),
                                           cp.p_rail_in_world - cp.p_section_centre_in_world, Eigen::Vector3d::Zero());
    // The nodal loads W f, summed per influence column (contacts on one element share its columns).
    const Eigen::Matrix<double, 12, 1> df = Lc.W * Lc.f;
    for (int j = 0; j < 12; ++j) {
      if (df(j) == 0.0) continue;
      const int node = Lc.element + j / kNodeDofs;
      const int col = im.node_slot[Lc.rail][static_cast<std::size_t>(node)] * kNodeDofs + j % kNodeDofs;
      if (!im.column_used[static_cast<std::size_t>(col)]) {
        im.column_used[static_cast<std::size_t>(col)] = 1;
        im.used_columns.push_back(col);
      }
      im.column_load[static_cast<std::size_t>(col)] += df(j);
    }
  }
  for (int e = 0; e < m; ++e) {
    const Implicit::Link& Le = im.links[static_cast<std::size_t>(e)];
    if (e > 0 && im.links[static_cast<std::size_t>(e - 1)].wheel == Le.wheel) continue;
    const rc::WheelState& ws = states.wheels[static_cast<std::size_t>(Le.frame_index)];
    rc::WheelContactResult& res = result_[static_cast<std::size_t>(Le.wheel)];
    rc::sumContactWrenches(ws.p_wheel_in_world, ws.R_wheelset_to_world, res);
    writeWrench(Le.frame_index, ws, res, out);
  }
}

// d = x_b + K_eff^{-1} W f over the DOFs [begin, end): the step's nodal loads, summed per influence column
// by applyLinkForces.
void CosimTrack::addColumnLoads(int begin, int end) noexcept {
  if (!implicit_) return;
  // Part of the contact forces' cost in the step; beside, part of the completion (track_rhs).
  ForcesTime timing(solve_beside_ ? nullptr : contact_cost_);
  Implicit& im = *implicit_;
  Eigen::VectorXd& d_new = integ().stepDisplacement();
  for (const int col : im.used_columns) {
    const std::size_t c = static_cast<std::size_t>(col);
    const int first = std::max(im.lo[c], begin), last = std::min(im.lo[c] + im.len[c], end);
    if (first >= last) continue;
    addScaledColumn(d_new.data() + first,
                    im.values.data() + c * static_cast<std::size_t>(im.window) + (first - im.lo[c]), im.column_load[c],
                    last - first);
  }
}

void CosimTrack::clearColumnLoads() noexcept {
  if (!implicit_) return;
  Implicit& im = *implicit_;
  for (const int col : im.used_columns) {
    im.column_load[static_cast<std::size_t>(col)] = 0.0;
    im.column_used[static_cast<std::size_t>(col)] = 0;
  }
  im.used_columns.clear();
}

int CosimTrack::sectionCount() const { return fe_ ? fe_->sectionCount() : static_cast<int>(sections_.size()); }

int CosimTrack::addSection(double s) {
  if (fe_) return fe_->addSection(s);
  if (!(s >= geometry_->sStart() && s <= geometry_->sEnd())) {
    std::ostringstream os;
    os << "deflection section at s = " << s << " m is not on the track [" << geometry_->sStart() << ", "
       << geometry_->sEnd() << "] m";
    throw std::runtime_error(os.str());
  }
  Section sec;
  sec.arc_length = s;
  makeZeroRailProbes(sec.rail);
  sections_.push_back(sec);
  return static_cast<int>(sections_.size()) - 1;
}

void CosimTrack::sectionDeflection(int i, RailSectionDeflection& out) const {
  rail::core::CostClock::Scope timing(cost_, rail::core::CostClock::kRailDeflection);
  if (fe_) {
    fe_->sectionDeflection(i, out);
    return;
  }
  const Section& sec = sections_[static_cast<std::size_t>(i)];
  out.arc_length = sec.arc_length;
  evalRailProbes(sec.rail, Eigen::VectorXd(), out);
}

void CosimTrack::sectionDeflection(int i, const Eigen::VectorXd& d, RailSectionDeflection& out) const {
  if (full_ == nullptr)
    throw std::runtime_error(
        "CosimTrack::sectionDeflection(i, d, out): only with the full-length flexible track (a window's DOFs "
        "change at every move); use sectionDeflection(i, out)");
  full_->sectionDeflection(i, d, out);
}

bool CosimTrack::energy(double& kinetic, double& potential) const noexcept {
  kinetic = potential = 0.0;
  if (!fe_) return false;
  fe_->energy(kinetic, potential);
  return true;
}

}  // namespace track
}  // namespace rail
