#include "rail_track_node/end_reflection.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include <rail_contact/format.hpp>

#include "rail_track_node/newmark.hpp"
#include "rail_track_node/track_mesh.hpp"
#include "rail_track_node/track_model.hpp"

namespace rail {
namespace track {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Euler-Bernoulli rail (bending stiffness EI, mass per length m) on a smeared foundation k_f: the
// propagating flexural wave has omega^2 = (EI kappa^4 + k_f) / m, group velocity d omega / d kappa =
// 2 EI kappa^3 / (m omega).
struct FlexuralWave {
  double EI, m, k_f;
  double cutOff() const { return std::sqrt(k_f / m) / (2.0 * kPi); }
  double groupVelocity(double f) const {
    const double w = 2.0 * kPi * f;
    const double kappa4 = (m * w * w - k_f) / EI;
    if (!(kappa4 > 0.0)) return 0.0;
    return 2.0 * EI * std::pow(kappa4, 0.75) / (m * w);
  }
};

// Velocity of the left rail in the measured direction at the rail node nearest arc length s, recorded
// while the burst pushes it at s_load, over n steps.
std::vector<double> record(const TrackModel& model, const EndReflectionOptions& o, double s_load, double s_obs,
                           int n_steps) {
  const TrackMesh& mesh = model.mesh;
  const int dof = o.lateral ? 1 : 2;
  const double ds = mesh.sleeper_spacing / mesh.rail_elements_between_sleepers;
  const int k_obs = static_cast<int>(std::lround((s_obs - mesh.s_start) / ds));
  if (k_obs < 0 || k_obs >= static_cast<int>(mesh.rail_nodes[kLeftRail].size()))
    throw std::invalid_argument("measureEndReflection: observation point off the rail");
  const int i_obs = mesh.dofIndex(mesh.rail_nodes[kLeftRail][static_cast<std::size_t>(k_obs)], dof);
  NewmarkIntegrator integ(model.system, o.dt, false);
  NewmarkState st = integ.initialState(Eigen::VectorXd::Zero(model.system.size()));
  NodalLoads loads(64);
  const double T = o.cycles / o.frequency;
  std::vector<double> v;
  v.reserve(static_cast<std::size_t>(n_steps));
  for (int n = 1; n <= n_steps; ++n) {
    const double t = n * o.dt;
    double f = 0.0;
    if (t < T) f = 1e4 * std::sin(2.0 * kPi * o.frequency * t) * std::pow(std::sin(kPi * t / T), 2);
    loads.clear();
    const Eigen::Vector3d force = o.lateral ? Eigen::Vector3d(0.0, f, 0.0) : Eigen::Vector3d(0.0, 0.0, -f);
    if (!addRailPointLoad(mesh, kLeftRail, s_load, force, Eigen::Vector3d::Zero(), loads))
      throw std::invalid_argument("measureEndReflection: load point off the rail");
    integ.step(st, loads);
    v.push_back(st.v(i_obs));
  }
  return v;
}

}  // namespace

EndReflectionResult measureEndReflection(const TrackData& data, const EndReflectionOptions& o) {
  if (!(o.frequency > 0.0) || o.cycles < 1 || !(o.dt > 0.0))
    throw std::invalid_argument("measureEndReflection: frequency, cycles and dt must be positive");
  const double a = data.layout.sleeper_spacing;
  if (!(o.observe_from_end > 0.0 && o.observe_from_end < o.load_from_end && o.load_from_end < o.length))
    throw std::invalid_argument("measureEndReflection: need 0 < observe_from_end < load_from_end < length");

  double k_lat = 0.0, k_vert = 0.0;
  foundationModuli(data, k_lat, k_vert);
  const FlexuralWave wave{data.rail.E * (o.lateral ? data.rail.I_z : data.rail.I_y), data.rail.rho * data.rail.A,
                          o.lateral ? k_lat : k_vert};
  EndReflectionResult r;
  r.cut_off_frequency = wave.cutOff();
  r.group_velocity = wave.groupVelocity(o.frequency);
  if (!(o.frequency > 1.05 * r.cut_off_frequency))
    throw std::invalid_argument("measureEndReflection: " + contact::formatNumber(o.frequency) +
                                " Hz is not above the cut-off of " + contact::formatNumber(r.cut_off_frequency) +
                                " Hz: no flexural wave propagates to the end");

  // The burst's main lobe spans f (1 -+ 2 / cycles); its slow part sets the window (the echo of the right
  // end has passed the observation point: two burst lengths for its spread), its fast part how far the
  // reference track must extend so that its own ends' echoes arrive after the window.
  const double T = o.cycles / o.frequency;
  const double f_slow = std::max(o.frequency * (1.0 - 1.0 / o.cycles), 1.05 * r.cut_off_frequency);
  const double f_fast = o.frequency * (1.0 + 2.0 / o.cycles);
  const double echo_path = o.load_from_end + o.observe_from_end;
  r.window = 2.0 * T + echo_path / wave.groupVelocity(f_slow);
  const double c_fast = 1.5 * wave.groupVelocity(f_fast);  // 1.5: margin for the discrete, periodic track
  const double extension = a * std::ceil(std::max(0.0, 0.5 * (c_fast * r.window - echo_path)) / a);
  // The short track's left end is as far as that too: only its right end's echo is in the window.
  const double L = a * std::ceil(std::max(o.length, 0.5 * (c_fast * r.window + echo_path)) / a);
  r.short_length = L;
  r.reference_length = L + 2.0 * extension;
  const int n_steps = static_cast<int>(std::ceil(r.window / o.dt));

  MeshOptions short_mesh;
  short_mesh.track_length = L;
  short_mesh.s_start = 0.0;
  MeshOptions reference_mesh;
  reference_mesh.track_length = r.reference_length;
  reference_mesh.s_start = -extension;
  const TrackModel short_track = buildTrackModel(data, short_mesh, straightTrackFrames());
  const TrackModel reference = buildTrackModel(data, reference_mesh, straightTrackFrames());
  r.free_dofs_short = short_track.system.size();
  r.free_dofs_reference = reference.system.size();

  const double s_load = L - o.load_from_end, s_obs = L - o.observe_from_end;
  const std::vector<double> v_short = record(short_track, o, s_load, s_obs, n_steps);
  const std::vector<double> v_ref = record(reference, o, s_load, s_obs, n_steps);
  double incident = 0.0, reflected = 0.0;
  for (std::size_t i = 0; i < v_ref.size(); ++i) {
    incident += v_ref[i] * v_ref[i];
    reflected += (v_short[i] - v_ref[i]) * (v_short[i] - v_ref[i]);
  }
  r.reflected_energy_fraction = reflected / incident;
  return r;
}

}  // namespace track
}  // namespace rail
