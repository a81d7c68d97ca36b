// Accuracy of the vehicle alone against a reference run (prints its figures; not a test):
//   bench_vehicle_accuracy [--sample DT] <scene.yaml> <reference.csv> [method max_step rtol atol] ...
// The reference is the scene run with Adams capped at 5e-6 s (written to reference.csv on the first call,
// read back afterwards if its first line names the same scene, interval and results revision); each candidate (default:
// the scene's own settings, the vehicle alone uncapped) runs the whole scene. Both are sampled every DT (default 1 ms,
// the node's output rate; a finer DT resolves the flange impacts, which last about a millisecond). Printed per
// candidate: wall time per simulated second, and against the reference the largest difference of the leading wheelset's
// lateral and vertical displacement and attack angle on the straights and in the steady curve, and the
// count, peak and mean of its flange-force bursts (runs of samples with flange contact) in the transitions.
// method: bdf | adams | auto; max_step 0 = none; rtol/atol 0 = the scene's. Exit 1 when a run stops early.
#include <rail_core/scene_loader.hpp>

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "rail_contact/tool_args.hpp"
#include "rail_vehicle_node/vehicle_simulator.hpp"

namespace {

using namespace rail;

struct Sample {
  double t = 0.0, s = 0.0, lateral = 0.0, vertical = 0.0, attack = 0.0;
  double flange_left = 0.0, flange_right = 0.0;  // leading wheelset's normal forces on the flange surface [N]
};

struct Candidate {
  std::string method = "auto";
  double max_step = 0.0, rtol = 0.0, atol = 0.0;
};

std::vector<Sample> simulate(const core::Scene& base, const Candidate& c, double sample, double& wall_per_s,
                             bool& finished) {
  core::Scene scene = base;
  scene.effects.track_model = core::TrackModel::kRigid;
  scene.solver.vehicle_method = c.method == "bdf"     ? core::VehicleMethod::kBdf
                                : c.method == "adams" ? core::VehicleMethod::kAdams
                                                      : core::VehicleMethod::kAuto;
  if (c.rtol > 0.0) scene.solver.vehicle_rtol = c.rtol;
  if (c.atol > 0.0) scene.solver.vehicle_atol = c.atol;
  scene.solver.standalone_max_step = c.max_step;
  vehicle::VehicleSimulator sim(vehicle::resolveVehicle(scene), vehicle::SimulatorSettings());
  std::vector<Sample> out;
  const auto t0 = std::chrono::steady_clock::now();
  vehicle::RunStatus status = vehicle::RunStatus::kRunning;
  for (int i = 1; status == vehicle::RunStatus::kRunning; ++i) {
    status = sim.advanceTo(sample * i);
    const vehicle::WheelsetTrackOutput& w = sim.wheelsets().front();
    Sample x;
    x.t = sim.time();
    x.s = w.arc_length;
    x.lateral = w.lateral;
    x.vertical = w.vertical;
    x.attack = w.angle_of_attack;
    for (const contact::ContactPointResult& c : sim.contacts()[0].contact) {
      if (c.surface == contact::kFlange) x.flange_left += c.N;
    }
    for (const contact::ContactPointResult& c : sim.contacts()[1].contact) {
      if (c.surface == contact::kFlange) x.flange_right += c.N;
    }
    out.push_back(x);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  wall_per_s = wall / sim.time();
  const vehicle::IntegratorCounters k = sim.counters();
  std::printf(
      "%s max_step %g rtol %g atol %g (%s): %.2f s simulated, %.1f s wall, %.3f s per simulated s; steps %ld, "
      "RHS %ld + %ld for %ld Jacobians; %s %s\n",
      c.method.c_str(), c.max_step, scene.solver.vehicle_rtol, scene.solver.vehicle_atol,
      sim.method() == vehicle::IntegrationMethod::kBdf ? "BDF" : "Adams", sim.time(), wall, wall_per_s, k.steps,
      k.rhs_evals, k.rhs_evals_jacobian, k.jacobian_evals,
      status == vehicle::RunStatus::kFinished ? "finished" : "stopped:", sim.message().c_str());
  std::fflush(stdout);
  finished = status == vehicle::RunStatus::kFinished;
  return out;
}

// The reference's first line: what it was made from (scene hash, reference settings, sampling interval and
// kResultsRevision); a reference whose line differs is refused, not compared against.
const char* const kProvenanceHead = "# bench_vehicle_accuracy reference:";
const Candidate kReference{"adams", 5e-6, 0.0, 0.0};

std::string provenance(const core::Scene& scene, double sample) {
  char line[256];
  std::snprintf(line, sizeof line, "%s scene_hash %016llx, %s max_step %g s, sample %g s, results_revision %d",
                kProvenanceHead, static_cast<unsigned long long>(scene.hash), kReference.method.c_str(),
                kReference.max_step, sample, vehicle::kResultsRevision);
  return line;
}

bool write(const std::string& path, const std::string& provenance_line, const std::vector<Sample>& v) {
  std::ofstream f(path);
  if (!f) return false;
  f.precision(17);
  f << provenance_line << '\n' << "t,s,lateral,vertical,attack,flange_left,flange_right\n";
  for (const Sample& x : v) {
    f << x.t << ',' << x.s << ',' << x.lateral << ',' << x.vertical << ',' << x.attack << ',' << x.flange_left << ','
      << x.flange_right << '\n';
  }
  f.close();
  return static_cast<bool>(f);
}

// Reads a reference made with provenance_line; false with the reason in `error` when the file is from
// another scene, setting or build, or a line is not seven numbers. A missing file is `missing`, no error.
bool read(const std::string& path, const std::string& provenance_line, std::vector<Sample>& v, bool& missing,
          std::string& error) {
  std::ifstream f(path);
  missing = !f;
  if (missing) return false;
  std::string line;
  std::getline(f, line);
  if (line.rfind(kProvenanceHead, 0) != 0) {
    error = " has no provenance line (made by an older build); delete it to make a new reference";
    return false;
  }
  if (line != provenance_line) {
    error = " was made from another scene, setting or build:\n  it says: " + line.substr(2) +
            "\n  needed:  " + provenance_line.substr(2) + "\ndelete it to make a new reference";
    return false;
  }
  std::getline(f, line);  // the column names
  for (int number = 3; std::getline(f, line); ++number) {
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream is(line);
    Sample x;
    is >> x.t >> x.s >> x.lateral >> x.vertical >> x.attack >> x.flange_left >> x.flange_right;
    std::string rest;
    if (is.fail() || (is >> rest)) {
      error = ":" + std::to_string(number) +
              ": expected seven numbers (t,s,lateral,vertical,attack,flange_left,flange_right)";
      return false;
    }
    v.push_back(x);
  }
  if (v.empty()) error = " has no samples";
  return !v.empty();
}

struct Bursts {
  int count = 0;
  double peak = 0.0, mean = 0.0;  // [N]; mean over the samples in contact
  double mean_peak = 0.0;         // mean of the bursts' own peaks [N]
};

// Flange-force bursts of the wheel with the larger total in [t0, t1].
Bursts flangeBursts(const std::vector<Sample>& v, double t0, double t1) {
  double left = 0.0, right = 0.0;
  for (const Sample& x : v) {
    if (x.t >= t0 && x.t <= t1) left += x.flange_left, right += x.flange_right;
  }
  const bool use_left = left > right;
  Bursts b;
  bool in = false;
  int n = 0;
  double burst_peak = 0.0;
  for (const Sample& x : v) {
    if (x.t < t0 || x.t > t1) continue;
    const double f = use_left ? x.flange_left : x.flange_right;
    if (f > 0.0) {
      if (!in) ++b.count, burst_peak = 0.0;
      in = true;
      b.peak = std::max(b.peak, f);
      burst_peak = std::max(burst_peak, f);
      b.mean += f;
      ++n;
    } else {
      if (in) b.mean_peak += burst_peak;
      in = false;
    }
  }
  if (in) b.mean_peak += burst_peak;
  if (n > 0) b.mean /= n;
  if (b.count > 0) b.mean_peak /= b.count;
  return b;
}

const char* const kUsage =
    "usage: bench_vehicle_accuracy [--sample DT] scene.yaml reference.csv [method max_step rtol atol] ...\n"
    "Accuracy of the vehicle alone against a reference run (Adams capped at 5e-6 s, written to reference.csv\n"
    "on the first call): per candidate the wall time per simulated second and the largest differences of the\n"
    "leading wheelset on the straights and the steady curve, and its flange-force bursts in the transitions.\n"
    "method: bdf | adams | auto; max_step 0 = none; rtol/atol 0 = the scene's. --sample: the sampling\n"
    "interval of both runs in s (default 1e-3). A reference.csv is reused only when its first line matches\n"
    "this run (scene hash, sampling interval, results revision of the build); otherwise exit 2.\n"
    "Exit 1 when a run stops before the scene's end (a stopped reference is not written), 2 on bad arguments.\n";
}  // namespace

namespace {
int runBenchmark(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, rail::tools::kOwnOptions)) return 0;
  double sample = 1e-3;
  int first = 1;
  if (argc > 2 && std::string(argv[1]) == "--sample") {
    char* end = nullptr;
    sample = std::strtod(argv[2], &end);
    if (end == argv[2] || *end != '\0' || !(sample > 0.0 && sample <= 0.1)) {
      std::fprintf(stderr, "bench_vehicle_accuracy: --sample: expected an interval in (0, 0.1] s, got '%s'\n", argv[2]);
      return 2;
    }
    first = 3;
  }
  std::vector<char*> rest{argv[0]};  // the arguments after --sample
  for (int i = first; i < argc; ++i) rest.push_back(argv[i]);
  rail::tools::refuseOptions(static_cast<int>(rest.size()), rest.data(), kUsage);
  if (argc - first < 2) {
    std::fputs(kUsage, stderr);
    return 2;
  }
  // Candidates in groups of four, each word one of its choices and each number >= 0.
  if ((argc - first - 2) % 4 != 0) {
    std::fprintf(
        stderr,
        "bench_vehicle_accuracy: %d candidate arguments, expected groups of four (method max_step rtol atol)\n%s",
        argc - first - 2, kUsage);
    return 2;
  }
  static const char* const kMethods[] = {"bdf", "adams", "auto", nullptr};
  std::vector<Candidate> candidates;
  for (int i = first + 2; i + 3 < argc; i += 4) {
    Candidate c;
    c.method = kMethods[tools::positionalChoice(argc, argv, i, kMethods, 2, kUsage)];
    c.max_step = tools::positionalNumber(argc, argv, i + 1, 0.0, 0.0, kUsage);
    c.rtol = tools::positionalNumber(argc, argv, i + 2, 0.0, 0.0, kUsage);
    c.atol = tools::positionalNumber(argc, argv, i + 3, 0.0, 0.0, kUsage);
    candidates.push_back(c);
  }
  const core::Scene scene = core::loadSceneFile(argv[first]);
  const std::string reference_path = argv[first + 1];
  const std::string provenance_line = provenance(scene, sample);
  std::vector<Sample> ref;
  bool missing = false;
  std::string error;
  const bool have_reference = read(reference_path, provenance_line, ref, missing, error);
  if (!have_reference && !missing) {
    std::fprintf(stderr, "bench_vehicle_accuracy: %s%s\n", reference_path.c_str(), error.c_str());
    return 2;
  }
  const std::filesystem::path reference_dir = std::filesystem::path(reference_path).parent_path();
  if (!have_reference && ::access(reference_dir.empty() ? "." : reference_dir.c_str(), W_OK) != 0) {
    std::fprintf(stderr, "bench_vehicle_accuracy: %s: cannot write the reference there (%s)\n", reference_path.c_str(),
                 std::strerror(errno));
    return 1;
  }
  if (!have_reference) {
    double wall = 0.0;
    bool finished = false;
    ref = simulate(scene, kReference, sample, wall, finished);
    if (!finished) {
      std::fprintf(stderr, "bench_vehicle_accuracy: the reference run stopped before the scene's end; %s not written\n",
                   reference_path.c_str());
      return 1;
    }
    if (!write(reference_path, provenance_line, ref)) {
      std::fprintf(stderr, "bench_vehicle_accuracy: %s: cannot write the reference\n", reference_path.c_str());
      return 1;
    }
  }
  if (candidates.empty()) candidates.push_back(Candidate{});
  // Windows by the leading wheelset's arc length on the paper scene's layout: straight 0-100 m, transition
  // 100-200 m, circle 200-380 m, transition 380-480 m, straight 480-500 m; a transition's effect on the
  // steady parts is left out for 20 m after it.
  struct Window {
    const char* name;
    double s0, s1;
  };
  const Window steady[] = {{"straight", 0.0, 100.0}, {"steady curve", 220.0, 380.0}, {"final straight", 485.0, 500.0}};
  const Window transitions[] = {{"entry transition", 100.0, 220.0}, {"exit transition", 380.0, 485.0}};
  bool all_finished = true;
  for (const Candidate& c : candidates) {
    double wall = 0.0;
    bool finished = false;
    const std::vector<Sample> run = simulate(scene, c, sample, wall, finished);
    all_finished = all_finished && finished;
    const std::size_t n = std::min(run.size(), ref.size());
    std::printf("| window | max |d lateral| [m] | max |d vertical| [m] | max |d attack| [deg] |\n|---|---|---|---|\n");
    for (const Window& w : steady) {
      double dl = 0.0, dv = 0.0, da = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        if (ref[k].s < w.s0 || ref[k].s > w.s1) continue;
        dl = std::max(dl, std::abs(run[k].lateral - ref[k].lateral));
        dv = std::max(dv, std::abs(run[k].vertical - ref[k].vertical));
        da = std::max(da, std::abs(run[k].attack - ref[k].attack) * 180.0 / M_PI);
      }
      std::printf("| %s (s %.0f-%.0f m) | %.2e | %.2e | %.2e |\n", w.name, w.s0, w.s1, dl, dv, da);
    }
    std::printf(
        "| transition | bursts (ref) | peak [kN] (ref) | mean burst peak [kN] (ref) | mean [kN] (ref) | count / "
        "peak / mean burst peak / mean differences |\n|---|---|---|---|---|---|\n");
    for (const Window& w : transitions) {
      double t0 = 1e9, t1 = -1e9;
      for (const Sample& x : ref) {
        if (x.s >= w.s0 && x.s <= w.s1) t0 = std::min(t0, x.t), t1 = std::max(t1, x.t);
      }
      const Bursts a = flangeBursts(run, t0, t1), b = flangeBursts(ref, t0, t1);
      const auto rel = [](double x, double y) { return y != 0.0 ? 100.0 * (x - y) / y : 0.0; };
      std::printf(
          "| %s (t %.2f-%.2f s) | %d (%d) | %.1f (%.1f) | %.1f (%.1f) | %.1f (%.1f) | %+.1f %% / %+.1f %% / "
          "%+.1f %% / %+.1f %% |\n",
          w.name, t0, t1, a.count, b.count, a.peak * 1e-3, b.peak * 1e-3, a.mean_peak * 1e-3, b.mean_peak * 1e-3,
          a.mean * 1e-3, b.mean * 1e-3, rel(a.count, b.count), rel(a.peak, b.peak), rel(a.mean_peak, b.mean_peak),
          rel(a.mean, b.mean));
    }
    std::fflush(stdout);
  }
  return all_finished ? 0 : 1;
}
}  // namespace

// A scene that cannot be read or built: one line naming the file and the field, exit 1.
int main(int argc, char** argv) {
  return rail::tools::runReportingErrors("bench_vehicle_accuracy", runBenchmark, argc, argv);
}
