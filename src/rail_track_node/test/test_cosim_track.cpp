// Track side of the co-simulation: rigid_fe gives exactly rail_contact's wrenches on the rigid rails and
// builds/integrates no FE track; flexible, with the default contact data (restitution 0.5) and the
// semi-implicit coupling, settles a standing wheelset to its static wheel loads with the rail deflected by
// the Winkler amount, and carries a rolling wheelset at 30 m/s with its static load on average, the
// sleeper-passing oscillation and no loss of contact; the explicit coupling chatters on the same data.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <rail_contact/profile.hpp>
#include <rail_core/cost_profile.hpp>
#include <rail_core/geometry_builder.hpp>
#include <rail_core/scene_loader.hpp>
#include <rail_core/testing/fixtures.hpp>

#include "rail_track_node/cosim_track.hpp"

namespace rt = rail::track;
namespace rc = rail::contact;
namespace cc = rail::core::coupling;
using rail::core::Scene;

namespace {

// A straight 30 m track with the paper's data and the paper's coach (4 wheelsets, or fewer), Iberian gauge.
Scene scene(const std::string& track_model, double track_step = 2.0e-5, int wheelsets = 4) {
  char step[32];
  std::snprintf(step, sizeof step, "%.10g", track_step);
  const std::string text =
      "name: t\ntrack:\n  gauge: 1.668\n  cant_reference_width: 1.733\n  data: ../track/paper_track.yaml\n"
      "  segments:\n    - {type: straight, length: 30.0}\n"
      "vehicle:\n  data: ../vehicle/paper_coach.yaml\n  start_arc_length: 25.0\n  speed: 0.0\n"
      "  back_to_back: 1.592\n  nominal_radius: 0.445\n  wheelsets: " +
      std::to_string(wheelsets) +
      "\n"
      "effects:\n  track_model: " +
      track_model +
      "\n"
      "solver:\n  track_step: " +
      std::string(step) + "\n  vehicle_max_step: " + std::string(step) + "\n  end: {time: 1.0}\n";
  return rail::core::fixtures::sceneFromText(text, "t.yaml");
}

// The contact of one wheel built independently, the way the vehicle side builds it on the rigid track.
struct DirectContact {
  explicit DirectContact(const Scene& sc)
      : track(rail::core::buildTrackGeometry(sc)),
        wheel(rc::makeS1002()),
        rail(rail::core::railProfileCurve(sc)),
        model(wheel, sc.vehicle.nominal_radius, rail, Eigen::Vector2d(0.0, -rc::uic60::kCentroidDepth), options(sc)),
        taping_y(0.5 * sc.vehicle.back_to_back + rc::flangeBackY(wheel)) {}
  static rc::WheelContactOptions options(const Scene& sc) {
    rc::WheelContactOptions o;
    o.flange_contact = sc.effects.flange_contact;
    o.spin = sc.effects.spin_creepage;
    return o;
  }
  // Vertical force (N) on the left wheel of a centred, level wheelset at rest with its taping-line
  // points at height z (m) on the rigid straight track.
  double verticalForce(double s, double z) const {
    rc::WheelState ws;
    ws.p_wheel_in_world = Eigen::Vector3d(s, taping_y, z);
    ws.arc_length = s;
    rc::WheelContactWork work;
    rc::WheelContactResult res;
    model.evaluate(ws, rc::RailSide::kLeft, track, rc::RigidRailDeformation(), work, res);
    return res.wheel_centre.force_in_world.z();
  }
  // Height (m) at which the vertical force is Q (N): bisection to 1e-12 m on the monotone force.
  double settledHeight(double s, double Q) const {
    const double r0 = model.detector().nominalRadius();
    double lo = r0 - 2e-3, hi = r0 + 1e-3;
    for (int i = 0; i < 60 && hi - lo > 1e-12; ++i) {
      const double mid = 0.5 * (lo + hi);
      (verticalForce(s, mid) > Q ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }
  rc::TrackGeometry track;
  rc::WheelProfile wheel;
  rc::ProfileCurve rail;
  rc::WheelContactModel model;
  double taping_y;
};

// Wheel `id` of a wheelset with its centre at (s, 0, z) rotated by R, moving at v, spinning at omega.
void setWheel(cc::WheelStateFrame& f, int id, double s, double taping_y, double z, const Eigen::Quaterniond& q,
              const Eigen::Vector3d& v, const Eigen::Vector3d& omega) {
  cc::WheelState& w = f.wheels[static_cast<std::size_t>(id)];
  w.id = static_cast<std::uint32_t>(id);
  const double y = (id % 2 == 0) ? taping_y : -taping_y;
  w.p_wheel_in_world = Eigen::Vector3d(s, 0.0, z) + q * Eigen::Vector3d(0.0, y, 0.0);
  w.arc_length = s;
  w.R_wheelset_to_world = q.toRotationMatrix();
  w.v_wheel_in_world = v + omega.cross(q * Eigen::Vector3d(0.0, y, 0.0));
  w.omega_wheelset_in_world = omega;
}

constexpr double kStations[4] = {25.0, 22.3, 8.6, 5.9};  // paper coach: 2.7 m bogie wheelbase

}  // namespace

// (a) rigid_fe: eight wheels at the settled height for Q = 72.9 kN, rolling at 30 m/s with a little
// creep, yaw and lateral offset, over 6 steps: the track side's wrenches equal rail_contact's evaluation
// on the rigid rails with the vehicle side's construction (own warm starts per wheel, same inputs).
// Same arithmetic on the same inputs: identical up to round-off, 1e-9 relative.
TEST(CosimTrack, RigidFeGivesRailContactWrenches) {
  const Scene sc = scene("rigid_fe");
  rt::CosimTrack track(rt::resolveCosimTrack(sc));
  ASSERT_EQ(track.wheelCount(), 8);
  const DirectContact direct(sc);
  const double Q = 72937.0;  // N, the paper wheelset's static wheel load (README: contact geometry)
  const double z = direct.settledHeight(kStations[0], Q);
  // The settled height gives Q on the rigid track (bisection to 1e-12 m: within 1e-3 N).
  EXPECT_NEAR(direct.verticalForce(kStations[0], z), Q, 1e-3 * Q);

  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  frame.count = 8;
  std::vector<rc::WheelContactWork> work(8);
  const double V = 30.0, r0 = sc.vehicle.nominal_radius, h = sc.solver.track_step;
  for (int k = 0; k < 6; ++k) {
    frame.step = static_cast<std::uint64_t>(k);
    frame.time = k * h;
    for (int ws = 0; ws < 4; ++ws) {
      const double yaw = 1e-3 * (ws - 1.5);
      const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
      const Eigen::Vector3d v(V, 0.02 * ws, 0.0);
      const Eigen::Vector3d omega = q * Eigen::Vector3d(0.0, (1.0 + 1e-3 * ws) * V / r0, 0.0);
      const double s = kStations[ws] + V * k * h;
      for (int side = 0; side < 2; ++side)
        setWheel(frame, 2 * ws + side, s, direct.taping_y, z - 1e-5 * ws, q, v, omega);
      // Lateral offset of 1 mm per wheelset.
      for (int side = 0; side < 2; ++side) frame.wheels[2 * ws + side].p_wheel_in_world.y() += 1e-3 * ws;
    }
    ASSERT_EQ(track.step(frame, out), rt::CosimStepStatus::kOk);
    ASSERT_EQ(out.count, 8u);
    for (int i = 0; i < 8; ++i) {
      const rc::WheelState& ws = frame.wheels[static_cast<std::size_t>(i)];
      rc::WheelContactResult res;
      direct.model.evaluate(ws, i % 2 == 0 ? rc::RailSide::kLeft : rc::RailSide::kRight, direct.track,
                            rc::RigidRailDeformation(), work[static_cast<std::size_t>(i)], res);
      const Eigen::Vector3d f = res.wheel_centre.force_in_world;
      const Eigen::Vector3d n = ws.R_wheelset_to_world * res.wheel_centre.moment_in_wheelset;
      const cc::WheelWrench& w = out.wheels[static_cast<std::size_t>(i)];
      EXPECT_EQ(w.id, ws.id);
      EXPECT_GT(f.z(), 0.5 * Q) << "wheel " << i << " not loaded: the test would compare zeros";
      EXPECT_LE((w.f_wheel_in_world - f).norm(), 1e-9 * f.norm()) << "step " << k << " wheel " << i;
      EXPECT_LE((w.n_wheel_in_world - n).norm(), 1e-9 * std::max(1.0, n.norm())) << "step " << k << " wheel " << i;
      // The contact results kept for output are the same contact points.
      EXPECT_LE(
          (track.contact(i).contact[rc::kTread].p_contact_in_world - res.contact[rc::kTread].p_contact_in_world).norm(),
          1e-12);
    }
  }
  // The creep moments are there (spin about the axle from the longitudinal creep force).
  EXPECT_GT(out.wheels[2].n_wheel_in_world.norm(), 10.0);
}

// (c) rigid_fe builds no FE track and runs no Newmark step; flexible integrates one step per frame after
// step 0. Exact counts.
TEST(CosimTrack, RigidFeRunsNoFeIntegration) {
  const Scene rigid_sc = scene("rigid_fe");
  rt::CosimTrack rigid(rt::resolveCosimTrack(rigid_sc));
  EXPECT_FALSE(rigid.flexible());
  EXPECT_EQ(rigid.sceneTrack(), nullptr);
  EXPECT_EQ(rigid.state(), nullptr);
  EXPECT_EQ(rigid.railDeformation(), nullptr);
  double kinetic = -1.0, potential = -1.0;
  EXPECT_FALSE(rigid.energy(kinetic, potential));  // no FE state, no energy
  EXPECT_EQ(kinetic + potential, 0.0);
  const Scene flex_sc = scene("flexible", 1e-4);
  rt::CosimTrack flex(rt::resolveCosimTrack(flex_sc));
  EXPECT_TRUE(flex.flexible());
  ASSERT_NE(flex.sceneTrack(), nullptr);
  EXPECT_GT(flex.sceneTrack()->model.system.size(), 0);

  const DirectContact direct(rigid_sc);
  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  frame.count = 8;
  for (int i = 0; i < 8; ++i)
    setWheel(frame, i, kStations[i / 2], direct.taping_y, 0.445, Eigen::Quaterniond::Identity(),
             Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  for (int k = 0; k < 5; ++k) {
    frame.step = static_cast<std::uint64_t>(k);
    ASSERT_EQ(rigid.step(frame, out), rt::CosimStepStatus::kOk);
    ASSERT_EQ(flex.step(frame, out), rt::CosimStepStatus::kOk);
  }
  EXPECT_EQ(rigid.framesStepped(), 5);
  EXPECT_EQ(rigid.newmarkSteps(), 0);
  EXPECT_EQ(flex.newmarkSteps(), 4);
  // Sections on the rigid track read zero.
  const int sec = rigid.addSection(15.0);
  rt::RailSectionDeflection d;
  rigid.sectionDeflection(sec, d);
  EXPECT_EQ(d.displacement[0].norm() + d.rotation[1].norm(), 0.0);
}

// The scene is resolved once, and refused there with its file named; the track takes only the setup.
TEST(CosimTrack, ResolvingRefusesScenesWithoutATrackSide) {
  auto message = [](const Scene& sc) {
    try {
      rt::resolveCosimTrack(sc);
    } catch (const rail::core::SceneError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  EXPECT_EQ(message(scene("rigid")),
            "t.yaml: effects.track_model: rigid runs the vehicle alone; the track side needs rigid_fe or flexible");
  Scene no_vehicle = scene("rigid_fe");
  no_vehicle.has_vehicle = false;
  EXPECT_EQ(message(no_vehicle), "t.yaml: the co-simulation track needs a vehicle (none in the scene)");
  // rigid_fe: the rails' geometry only, no FE line.
  const rt::CosimTrackSetup rigid = rt::resolveCosimTrack(scene("rigid_fe"));
  EXPECT_FALSE(rigid.line.has_value());
  EXPECT_TRUE(rigid.rigid_geometry.has_value());
  EXPECT_EQ(rigid.wheel_count, 8);
  // A hand-made setup without wheels is refused by the track, naming the setup's source.
  rt::CosimTrackSetup none = rt::resolveCosimTrack(scene("rigid_fe"));
  none.wheel_count = 0;
  try {
    rt::CosimTrack track(std::move(none));
    ADD_FAILURE() << "a track without wheels was built";
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), "t.yaml: the track needs at least one wheel, got 0");
  }
}

// A frame with the wrong wheel count or a repeated id is refused and changes nothing.
TEST(CosimTrack, RefusesMalformedFrames) {
  rt::CosimTrack track(rt::resolveCosimTrack(scene("rigid_fe")));
  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  frame.count = 6;
  EXPECT_EQ(track.step(frame, out), rt::CosimStepStatus::kWrongWheelCount);
  frame.count = 8;
  for (int i = 0; i < 8; ++i) frame.wheels[static_cast<std::size_t>(i)].id = static_cast<std::uint32_t>(i);
  frame.wheels[3].id = 2;
  EXPECT_EQ(track.step(frame, out), rt::CosimStepStatus::kBadWheelId);
  frame.wheels[3].id = 9;
  EXPECT_EQ(track.step(frame, out), rt::CosimStepStatus::kBadWheelId);
  EXPECT_EQ(track.framesStepped(), 0);
  EXPECT_EQ(out.count, 0u);
}

namespace {

// Static vertical displacement (m) of the left wheel's rail contact point at arc length s0 of the FE track
// (centre line and section rotation, beam shape functions): under gravity alone, and under gravity plus
// the rail wrenches of both wheels of a centred wheelset at height z on the rigid rails (one static solve
// each). Also the section index added at s0 and the static solution with the wheel loads.
struct StaticContact {
  double dz_gravity = 0.0, dz_loaded = 0.0, Fz = 0.0;  // m, m, N (wheel load of the rigid evaluation)
  int section = 0;
  Eigen::VectorXd d_loaded, d_gravity;
};
StaticContact staticContact(rt::CosimTrack& track, const DirectContact& direct, double s0, double z) {
  const rt::SceneTrack& st = *track.sceneTrack();
  const rt::LinearSystem& sys = st.model.system;
  rt::NodalLoads loads(64);
  Eigen::Vector3d arm = Eigen::Vector3d::Zero();
  StaticContact out;
  for (int side = 0; side < 2; ++side) {
    rc::WheelState ws;
    ws.p_wheel_in_world = Eigen::Vector3d(s0, side == 0 ? direct.taping_y : -direct.taping_y, z);
    ws.arc_length = s0;
    rc::WheelContactWork work;
    rc::WheelContactResult res;
    direct.model.evaluate(ws, side == 0 ? rc::RailSide::kLeft : rc::RailSide::kRight, direct.track,
                          rc::RigidRailDeformation(), work, res);
    const rc::ContactPointResult& c = res.contact[rc::kTread];
    EXPECT_TRUE(c.active);
    EXPECT_TRUE(rt::addRailPointLoad(
        st.model.mesh, side == 0 ? rt::kLeftRail : rt::kRightRail, c.s_r, -c.force_on_wheel_in_world,
        (c.p_rail_in_world - c.p_section_centre_in_world).cross(-c.force_on_wheel_in_world), loads));
    if (side == 0) {
      arm = c.p_rail_in_world - c.p_section_centre_in_world;
      out.Fz = res.wheel_centre.force_in_world.z();
    }
  }
  Eigen::VectorXd f = sys.f_gravity;
  for (int k = 0; k < loads.size(); ++k) f(loads.index(k)) += loads.value(k);
  out.d_loaded = rt::solveStatic(sys, f);
  out.d_gravity = rt::staticGravityDeflection(sys);
  out.section = track.addSection(s0);
  rt::RailSectionDeflection loaded, gravity;
  track.sectionDeflection(out.section, out.d_loaded, loaded);
  track.sectionDeflection(out.section, out.d_gravity, gravity);
  out.dz_loaded = loaded.displacement[0].z() + loaded.rotation[0].cross(arm).z();
  out.dz_gravity = gravity.displacement[0].z() + gravity.rotation[0].cross(arm).z();
  return out;
}

// Wheel-load histories of the two wheels of a one-wheelset scene over frames first_step .. first_step +
// T_end / h: the wheelset at arc length s(t) = s0 + V t (t from the run's start), centred and level,
// lowered smoothly over T_ramp from z_start to z_end and held there, spinning at V / r0. Also counts the
// wheel-steps after frame 0 with no normal force on a wheel (contact losses).
struct WheelsetRun {
  std::vector<double> t, Fz0, Fz1;
  long losses = 0;
};
WheelsetRun runWheelset(rt::CosimTrack& track, double taping_y, double s0, double V, double z_start, double z_end,
                        double T_ramp, double T_end, double h, long first_step = 0) {
  WheelsetRun run;
  cc::WheelStateFrame frame(2);
  cc::WrenchFrame out(2);
  frame.count = 2;
  const long n_steps = std::lround(T_end / h);
  for (long k = 0; k <= n_steps; ++k) {
    const double t = k * h, x = std::min(1.0, t / T_ramp);
    const double ramp = x * x * (3.0 - 2.0 * x), ramp_rate = t < T_ramp ? 6.0 * x * (1.0 - x) / T_ramp : 0.0;
    frame.step = static_cast<std::uint64_t>(first_step + k);
    frame.time = (first_step + k) * h;
    for (int side = 0; side < 2; ++side)
      setWheel(frame, side, s0 + V * t, taping_y, z_start + ramp * (z_end - z_start), Eigen::Quaterniond::Identity(),
               Eigen::Vector3d(V, 0.0, ramp_rate * (z_end - z_start)), Eigen::Vector3d(0.0, V / 0.445, 0.0));
    EXPECT_EQ(track.step(frame, out), rt::CosimStepStatus::kOk);
    run.t.push_back(t);
    run.Fz0.push_back(out.wheels[0].f_wheel_in_world.z());
    run.Fz1.push_back(out.wheels[1].f_wheel_in_world.z());
    for (int i = 0; i < 2; ++i)
      if (first_step + k > 0 &&
          !(track.contact(i).contact[rc::kTread].N > 0.0 || track.contact(i).contact[rc::kFlange].N > 0.0))
        ++run.losses;
  }
  return run;
}

// Complex amplitude of frequency f (Hz) in x(t) over t in [t0, t1) (a whole number of periods).
std::complex<double> harmonic(const std::vector<double>& t, const std::vector<double>& x, double f, double t0,
                              double t1) {
  std::complex<double> sum = 0.0;
  long n = 0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (t[k] < t0 - 1e-12 || t[k] >= t1 - 1e-12) continue;
    sum += x[k] * std::exp(std::complex<double>(0.0, -2.0 * M_PI * f * t[k]));
    ++n;
  }
  return 2.0 * sum / static_cast<double>(n);
}

double mean(const std::vector<double>& t, const std::vector<double>& x, double t0, double t1) {
  double sum = 0.0;
  long n = 0;
  for (std::size_t k = 0; k < t.size(); ++k)
    if (t[k] >= t0 - 1e-12 && t[k] < t1 - 1e-12) {
      sum += x[k];
      ++n;
    }
  return sum / static_cast<double>(n);
}

}  // namespace

// (b) flexible, default contact data (restitution e = 0.5) and coupling (semi-implicit): the leading
// wheelset stands still above the sleeper at mid-track (s = 15 m); the other three are lifted clear of the
// rails. The wheelset is lowered smoothly (20 ms) from the rigid track's settled height for Q = 100 kN per
// wheel by the static FE deflection of the contact point under those wheel loads (K d = f_g + f_c, one
// static solve), then held; after 0.15 s the track is at rest and:
//  - no step after the first loses contact (a wheel with no normal force);
//  - each wheel's vertical force is Q within 1 %: the Hertz penetration (~0.1 mm) is about 7 times
//    smaller than the rail deflection, so 1 % of Q is 0.7 micrometre of relative position; the static
//    reference neglects the small change of the contact point on the rolled rail and the creep forces the
//    standing wheel holds;
//  - the rail centre-line deflection under the wheel due to the wheel load is the Winkler value of
//    doc/fe.md for the paper's flexible sleeper, w0 = 0.781 mm per 100 kN (the FE model gave 0.996 w0
//    above a sleeper there), within 5 %: here the load acts at the contact point with its lateral part;
//  - that deflection is the reference static solve's within 1 % of w0 (the 1 % of the loads above).
// Deflection sections: off the rails they are refused, naming s and the rails' extent; on the rigid_fe
// track they read zero; on the flexible track at rest (self-weight state) they read the rails' sag.
TEST(CosimTrack, DeflectionSectionsOffTheRailsAreRefusedAndRigidRailsReadZero) {
  rt::CosimTrack rigid(rt::resolveCosimTrack(scene("rigid_fe")));
  try {
    rigid.addSection(100.0);
    FAIL() << "a section off the track was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("deflection section at s = 100 m is not on the track [", 0), 0u) << e.what();
  }
  rt::RailSectionDeflection out;
  ASSERT_EQ(rigid.addSection(15.0), 0);
  rigid.sectionDeflection(0, out);
  EXPECT_EQ(out.arc_length, 15.0);
  for (int r = 0; r < 2; ++r) {
    EXPECT_EQ(out.displacement[r].norm(), 0.0);
    EXPECT_EQ(out.rotation[r].norm(), 0.0);
  }
  rt::CosimTrack flexible(rt::resolveCosimTrack(scene("flexible")));
  try {
    flexible.addSection(100.0);
    FAIL() << "a section off the meshed rails was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).rfind("deflection section at s = 100 m is not on the meshed rails [", 0), 0u)
        << e.what();
  }
  ASSERT_EQ(flexible.addSection(15.0), 0);
  flexible.sectionDeflection(0, out);
  for (int r = 0; r < 2; ++r) {
    // Self-weight sag of the rail on its pads: downwards, well under a millimetre.
    EXPECT_LT(out.displacement[r].z(), 0.0);
    EXPECT_GT(out.displacement[r].z(), -1e-3);
  }
}

TEST(CosimTrack, FlexibleStandingWheelsetSettlesToStaticLoads) {
  const double h = 2e-5;
  const Scene sc = scene("flexible", h);
  rt::CosimTrack track(rt::resolveCosimTrack(sc));
  ASSERT_EQ(track.coupling(), rt::CosimCoupling::kSemiImplicit);
  ASSERT_EQ(track.contactModel().options().damping.restitution, 0.5);  // the default contact data
  const DirectContact direct(sc);
  const double s0 = 15.0, Q = 100000.0;
  const double z_rigid = direct.settledHeight(s0, Q);
  const StaticContact ref = staticContact(track, direct, s0, z_rigid);
  const double dz_contact = ref.dz_loaded;
  rt::RailSectionDeflection defl_static, defl_gravity;
  track.sectionDeflection(ref.section, ref.d_loaded, defl_static);
  track.sectionDeflection(ref.section, ref.d_gravity, defl_gravity);

  double kinetic0 = -1.0, potential0 = -1.0;  // the start is the self-weight equilibrium: zero energy
  ASSERT_TRUE(track.energy(kinetic0, potential0));
  EXPECT_NEAR(kinetic0, 0.0, 1e-12);
  EXPECT_NEAR(potential0, 0.0, 1e-9);

  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  frame.count = 8;
  const double T_ramp = 0.02, T_end = 0.15;
  const long n_steps = std::lround(T_end / h);
  long losses = 0;
  for (long k = 0; k <= n_steps; ++k) {
    const double t = k * h, x = std::min(1.0, t / T_ramp);
    const double ramp = x * x * (3.0 - 2.0 * x), ramp_rate = t < T_ramp ? 6.0 * x * (1.0 - x) / T_ramp : 0.0;
    frame.step = static_cast<std::uint64_t>(k);
    frame.time = t;
    for (int ws = 0; ws < 4; ++ws) {
      const double z = ws == 0 ? z_rigid + ramp * dz_contact : 0.445 + 0.05;
      const double vz = ws == 0 ? ramp_rate * dz_contact : 0.0;
      const double s = ws == 0 ? s0 : s0 - 2.7 * ws;
      for (int side = 0; side < 2; ++side)
        setWheel(frame, 2 * ws + side, s, direct.taping_y, z, Eigen::Quaterniond::Identity(),
                 Eigen::Vector3d(0.0, 0.0, vz), Eigen::Vector3d::Zero());
    }
    ASSERT_EQ(track.step(frame, out), rt::CosimStepStatus::kOk);
    for (int i = 0; i < 2; ++i)
      if (k > 0 && !(track.contact(i).contact[rc::kTread].N > 0.0)) ++losses;
  }
  EXPECT_EQ(track.newmarkSteps(), n_steps);
  EXPECT_EQ(losses, 0);
  for (int i = 0; i < 2; ++i)
    EXPECT_NEAR(out.wheels[static_cast<std::size_t>(i)].f_wheel_in_world.z(), Q, 0.01 * Q) << "wheel " << i;
  // Energy (effects.energy_output): at rest under the two wheel loads the track's energy counted from its
  // self-weight equilibrium is the work of the loads, 1/2 sum Q w_c (Clapeyron's theorem for a linear
  // elastic body), w_c = the contact point's deflection due to the load. Within 3 %: 1 % for the loads
  // above, plus the creep and lateral parts of the contact force (~2.5 % of Q on the tread's 1/40 slope)
  // that this vertical-only work leaves out. The kinetic part has decayed to below 1e-3 of it.
  double kinetic = -1.0, potential = -1.0;
  ASSERT_TRUE(track.energy(kinetic, potential));
  const double clapeyron = 2.0 * 0.5 * Q * (ref.dz_gravity - ref.dz_loaded);
  EXPECT_GT(clapeyron, 10.0);  // ~2 x 0.5 x 100 kN x 0.8 mm = 80 J: the check bites
  std::printf("track energy at rest: potential %.3f J, 1/2 sum Q w_c %.3f J, kinetic %.3g J\n", potential, clapeyron,
              kinetic);
  EXPECT_NEAR(potential, clapeyron, 0.03 * clapeyron);
  EXPECT_LT(kinetic, 1e-3 * potential);
  for (int i = 2; i < 8; ++i) EXPECT_EQ(out.wheels[static_cast<std::size_t>(i)].f_wheel_in_world.norm(), 0.0);

  rt::RailSectionDeflection now;
  track.sectionDeflection(ref.section, now);
  const double w0 = 0.781e-3 * Q / 100000.0;  // doc/fe.md: Winkler w0 for the paper's flexible sleeper
  for (int r = 0; r < 2; ++r) {
    const double w_wheel = -(now.displacement[r].z() - defl_gravity.displacement[r].z());
    EXPECT_NEAR(w_wheel, w0, 0.05 * w0) << "rail " << r;
    EXPECT_NEAR(now.displacement[r].z(), defl_static.displacement[r].z(), 0.01 * w0 + 1e-9) << "rail " << r;
  }
}

// The problem the semi-implicit coupling solves (doc/cosim_track.md): with the explicit coupling and the
// default contact data, the standing wheelset of the test above (lowered over 20 ms onto the flexible
// rails) oscillates: the damper of eq. 9 acts on a one-step-old rail velocity with a loop gain
// 2 c / (h k_rail) of about 2.2. While rail_contact's impact memory held the onset rate only, eq. 9's
// bracket went negative on separation and the wheels lost contact in every other step; with the largest
// approach rate since onset (hertz.hpp, ImpactMemory) the bracket stays within [0.44, 1.56] and contact is
// kept, but the load still swings (measured 49-144 kN about Q = 100 kN). Over t in [20, 30] ms at
// h = 2e-5 s: the explicit run's wheel load spans more than 0.5 Q peak to peak; the semi-implicit run's
// less than 0.1 Q (measured 97-103 kN) and it never loses contact.
TEST(CosimTrack, ExplicitCouplingChattersWithContactDampingSemiImplicitDoesNot) {
  const double h = 2e-5, s0 = 15.0, Q = 100000.0;
  const Scene sc = scene("flexible", h, 1);
  const DirectContact direct(sc);
  const double z_rigid = direct.settledHeight(s0, Q);
  long losses[2] = {0, 0};
  double span[2] = {0.0, 0.0};
  for (int scheme = 0; scheme < 2; ++scheme) {
    rt::CosimTrackOptions options;
    options.coupling = scheme == 0 ? rt::CosimCoupling::kExplicit : rt::CosimCoupling::kSemiImplicit;
    rt::CosimTrack track(rt::resolveCosimTrack(sc), options);
    const double dz = staticContact(track, direct, s0, z_rigid).dz_loaded;
    const WheelsetRun lowered = runWheelset(track, direct.taping_y, s0, 0.0, z_rigid, z_rigid + dz, 0.02, 0.02, h);
    const WheelsetRun held = runWheelset(track, direct.taping_y, s0, 0.0, z_rigid + dz, z_rigid + dz, 1e-3, 0.01, h,
                                         std::lround(0.02 / h) + 1);
    EXPECT_EQ(lowered.t.size() + held.t.size(), std::size_t(1502));
    losses[scheme] = held.losses;
    double lo = 1e300, hi = -1e300;
    for (const auto* f : {&held.Fz0, &held.Fz1})
      for (double x : *f) lo = std::min(lo, x), hi = std::max(hi, x);
    span[scheme] = hi - lo;
    std::printf("%s coupling: contact losses %ld, wheel loads %.1f .. %.1f kN\n",
                scheme == 0 ? "explicit" : "semi-implicit", held.losses, lo / 1e3, hi / 1e3);
  }
  EXPECT_GT(span[0], 0.5 * Q) << "explicit coupling: the load should swing";
  EXPECT_LT(span[1], 0.1 * Q) << "semi-implicit coupling";
  EXPECT_EQ(losses[1], 0) << "semi-implicit coupling";
}

// (e) flexible, default contact data and coupling: one wheelset rolls at V = 30 m/s over the 30 m track
// (s = 9 m .. 18 m in 0.3 s; sleepers every a = 0.6 m), at a constant height after a 20 ms lowering ramp.
// The height is the one whose quasi-static wheel load, averaged over a sleeper bay, is Q = 100 kN: at 12
// positions in a bay the static contact-point deflection under the wheel loads (one static solve each,
// linear in the load) and the rigid contact's load-penetration law give the load N_j at a given height.
// Over t in [0.1, 0.3) s (10 sleeper periods, after the ramp's transient):
//  - no contact loss on either wheel at any step;
//  - the mean wheel load is Q within 1 % (the quasi-static mean is Q; at 30 m/s, far below the track's
//    critical speed, the moving load changes the mean deflection by much less than that);
//  - the sleeper-passing component (V / a = 50 Hz) is present and bounded: its amplitude is between 0.7
//    and 1.5 times the quasi-static bay variation's first harmonic (the track's vertical resonance under a
//    wheel held at constant height is well above 50 Hz, so the dynamic amplification 1 / (1 - (f/f_n)^2)
//    stays near 1; 0.7 allows for the track damping, 1.5 for f_n down to 90 Hz);
//  - the same run at h = 1e-5 s gives the same wheel-load history within 0.1 % of Q at every common
//    time: the components that last (50 Hz and its harmonics, < 1 kHz) have omega h < 0.13 at
//    h = 2e-5 s, where Newmark's period error (omega h)^2 / 12 is below 0.15 %, and their amplitude is
//    below 1 % of Q;
//  - after the last step, the contact model evaluated on the FE rails at t_k (railDeformation()) gives the
//    force returned to the vehicle within 1e-5 of Q: the semi-implicit step solves the contact law at the
//    new state to first order in the rail motion of one step (here below a micrometre), to 1e-9 in force.
TEST(CosimTrack, FlexibleRollingWheelsetKeepsContactAndLoad) {
  const double V = 30.0, Q = 100000.0, a = 0.6, s0 = 9.0, T_ramp = 0.02, T_end = 0.3, t0 = 0.1;
  const Scene sc = scene("flexible", 2e-5, 1);
  rt::CosimTrack track(rt::resolveCosimTrack(sc));
  const DirectContact direct(sc);
  const double z_rigid = direct.settledHeight(s0, Q);

  // Quasi-static loads over the bay starting at the sleeper at s = 15 m (away from the ends).
  constexpr int kPositions = 12;
  double dz_gravity[kPositions], compliance[kPositions];  // m; m/N
  for (int j = 0; j < kPositions; ++j) {
    const StaticContact st = staticContact(track, direct, 15.0 + a * j / kPositions, z_rigid);
    dz_gravity[j] = st.dz_gravity;
    compliance[j] = (st.dz_loaded - st.dz_gravity) / st.Fz;
  }
  auto quasiStatic = [&](int j, double z) {  // N with N = F_rigid(z - dz(N)), bisection to 1e-6 N
    double lo = 0.0, hi = 3.0 * Q;
    for (int i = 0; i < 60 && hi - lo > 1e-6; ++i) {
      const double N = 0.5 * (lo + hi);
      (direct.verticalForce(15.0 + a * j / kPositions, z - (dz_gravity[j] + compliance[j] * N)) > N ? lo : hi) = N;
    }
    return 0.5 * (lo + hi);
  };
  auto bayMean = [&](double z) {
    double sum = 0.0;
    for (int j = 0; j < kPositions; ++j) sum += quasiStatic(j, z);
    return sum / kPositions;
  };
  double z_lo = z_rigid - 3e-3, z_hi = z_rigid;  // bay mean decreasing in z
  for (int i = 0; i < 60 && z_hi - z_lo > 1e-12; ++i) {
    const double mid = 0.5 * (z_lo + z_hi);
    (bayMean(mid) > Q ? z_lo : z_hi) = mid;
  }
  const double z = 0.5 * (z_lo + z_hi);
  std::complex<double> qs_harmonic = 0.0;
  for (int j = 0; j < kPositions; ++j)
    qs_harmonic += quasiStatic(j, z) * std::exp(std::complex<double>(0.0, -2.0 * M_PI * j / kPositions));
  const double A_qs = 2.0 * std::abs(qs_harmonic) / kPositions;
  ASSERT_NEAR(bayMean(z), Q, 1.0);
  ASSERT_GT(A_qs, 1e-3 * Q) << "the bay's stiffness variation must show in the quasi-static load";

  // Quasi-static limit: at 3 m/s (sleeper passing 5 Hz) the same amplitude within 5 %.
  {
    const double V_slow = 3.0, h_slow = 1e-4, T_slow = 0.1 + 2 * a / V_slow;
    rt::CosimTrack slow(rt::resolveCosimTrack(scene("flexible", h_slow, 1)));
    const WheelsetRun run =
        runWheelset(slow, direct.taping_y, 14.4 - 0.1 * V_slow, V_slow, z_rigid, z, T_ramp, T_slow, h_slow);
    EXPECT_EQ(run.losses, 0);
    for (const std::vector<double>* F : {&run.Fz0, &run.Fz1}) {
      EXPECT_NEAR(mean(run.t, *F, 0.1, T_slow), Q, 0.01 * Q);
      EXPECT_NEAR(std::abs(harmonic(run.t, *F, V_slow / a, 0.1, T_slow)), A_qs, 0.05 * A_qs);
    }
    std::printf("[ figures  ] quasi-static 5 Hz amplitude %.1f N; at 3 m/s: mean %.1f N, amplitude %.1f N\n", A_qs,
                mean(run.t, run.Fz0, 0.1, T_slow), std::abs(harmonic(run.t, run.Fz0, V_slow / a, 0.1, T_slow)));
  }

  const WheelsetRun run = runWheelset(track, direct.taping_y, s0, V, z_rigid, z, T_ramp, T_end, 2e-5);
  EXPECT_EQ(run.losses, 0);
  for (const std::vector<double>* F : {&run.Fz0, &run.Fz1}) {
    EXPECT_NEAR(mean(run.t, *F, t0, T_end), Q, 0.01 * Q);
    const double A = std::abs(harmonic(run.t, *F, V / a, t0, T_end));
    EXPECT_GT(A, 0.25 * A_qs) << "quasi-static amplitude " << A_qs << " N";
    EXPECT_LT(A, 2.0 * A_qs) << "quasi-static amplitude " << A_qs << " N";
  }
  std::printf("[ figures  ] 30 m/s, h = 2e-5 s: mean %.1f N, 50 Hz amplitude %.1f N, min %.1f N, max %.1f N\n",
              mean(run.t, run.Fz0, t0, T_end), std::abs(harmonic(run.t, run.Fz0, V / a, t0, T_end)),
              *std::min_element(run.Fz0.begin() + std::lround(t0 / 2e-5), run.Fz0.end()),
              *std::max_element(run.Fz0.begin() + std::lround(t0 / 2e-5), run.Fz0.end()));

  // The contact law at the new state: the model on the FE rails of t_k, with this step's contact memory.
  for (int i = 0; i < 2; ++i) {
    cc::WheelStateFrame frame(2);
    setWheel(frame, i, s0 + V * T_end, direct.taping_y, z, Eigen::Quaterniond::Identity(), Eigen::Vector3d(V, 0, 0),
             Eigen::Vector3d(0.0, V / 0.445, 0.0));
    const rc::WheelState& ws = frame.wheels[static_cast<std::size_t>(i)];
    rc::WheelContactWork work = track.contactWork(i);
    rc::WheelContactResult res;
    track.contactModel().evaluate(ws, i == 0 ? rc::RailSide::kLeft : rc::RailSide::kRight, track.geometry(),
                                  *track.railDeformation(), work, res);
    const double F_returned = (i == 0 ? run.Fz0 : run.Fz1).back();
    EXPECT_NEAR(res.wheel_centre.force_in_world.z(), F_returned, 1e-5 * Q) << "wheel " << i;
    std::printf("[ figures  ] wheel %d: contact model on the rails at t_k %.4f N, returned %.4f N\n", i,
                res.wheel_centre.force_in_world.z(), F_returned);
  }

  // Half the step: the same history within 0.1 % of Q.
  rt::CosimTrack fine(rt::resolveCosimTrack(scene("flexible", 1e-5, 1)));
  const WheelsetRun run_fine = runWheelset(fine, direct.taping_y, s0, V, z_rigid, z, T_ramp, T_end, 1e-5);
  EXPECT_EQ(run_fine.losses, 0);
  double worst = 0.0;
  for (std::size_t k = 0; k < run.t.size(); ++k) {
    if (run.t[k] < t0) continue;
    ASSERT_NEAR(run_fine.t[2 * k], run.t[k], 1e-12);
    worst = std::max(worst, std::abs(run_fine.Fz0[2 * k] - run.Fz0[k]));
  }
  EXPECT_LT(worst, 1e-3 * Q);
  std::printf("[ figures  ] h = 2e-5 s vs 1e-5 s: largest wheel-load difference %.1f N\n", worst);
}

// ---- Cost of the effects (rail_core/cost_profile.hpp): an effect that is off costs nothing. ----------
// The paper coach's 8 wheels at the height where the rigid rails would carry 72.9 kN, rolling at 10 m/s
// (spin = speed / nominal radius), for 25 track steps with a cost clock attached. Counts and sums of clock
// readings are compared, so "off" must give exactly 0 and "on" > 0.
namespace {

struct TrackCostRun {
  rail::core::CostClock clock;
  long newmark_steps = 0;
};

// sections / pads: call sectionDeflection / padForces after every step, as the track node does when
// effects.rail_deflection_output / pad_force_output are on (its only callers).
TrackCostRun runTrackWithClock(const Scene& sc, bool sections, bool pads, int steps = 25) {
  TrackCostRun r;
  rt::CosimTrackOptions options;
  options.cost = &r.clock;
  rt::CosimTrack track(rt::resolveCosimTrack(sc), options);
  const DirectContact direct(sc);
  const double z = direct.settledHeight(15.0, 72900.0), v = 10.0;
  const int section = sections ? track.addSection(15.0) : -1;
  std::vector<rt::PadForceSample> samples(static_cast<std::size_t>(std::max(1, track.sleeperCount())));
  rt::RailSectionDeflection defl;
  cc::WheelStateFrame frame(8);
  cc::WrenchFrame out(8);
  frame.count = 8;
  for (int k = 0; k <= steps; ++k) {
    frame.step = static_cast<std::uint64_t>(k);
    frame.time = k * sc.solver.track_step;
    for (int ws = 0; ws < 4; ++ws)
      for (int side = 0; side < 2; ++side)
        setWheel(frame, 2 * ws + side, kStations[ws] + v * frame.time, direct.taping_y, z,
                 Eigen::Quaterniond::Identity(), Eigen::Vector3d(v, 0.0, 0.0), Eigen::Vector3d(0.0, v / 0.445, 0.0));
    EXPECT_EQ(track.step(frame, out), rt::CosimStepStatus::kOk);
    if (sections) track.sectionDeflection(section, defl);
    if (pads) track.padForces(0.0, 30.0, samples.data(), static_cast<int>(samples.size()));
  }
  r.newmark_steps = track.newmarkSteps();
  return r;
}

using CC = rail::core::CostClock;

}  // namespace

TEST(CosimTrackCost, FlexibleStepIsSplitIntoContactRhsAndSolve) {
  const TrackCostRun r = runTrackWithClock(scene("flexible"), false, false);
  ASSERT_EQ(r.newmark_steps, 25);
  // One right-hand side and one K_eff solve per Newmark step (the completion is timed with the RHS).
  EXPECT_EQ(r.clock.calls[CC::kTrackSolve], 25);
  EXPECT_EQ(r.clock.calls[CC::kTrackRhs], 2 * 25);
  EXPECT_GT(r.clock.seconds[CC::kTrackSolve], 0.0);
  EXPECT_EQ(r.clock.contact.evaluations, 8 * 26);  // every wheel of every frame, step 0 included
  EXPECT_GT(r.clock.contact.detection_seconds, 0.0);
  EXPECT_GT(r.clock.contact.forces_seconds, 0.0);
  EXPECT_GT(r.clock.contact.creep_evaluations, 0);  // the wheels are in contact
  // No window, no outputs asked for: no cost there.
  EXPECT_EQ(r.clock.calls[CC::kWindowMoves], 0);
  EXPECT_EQ(r.clock.calls[CC::kRailDeflection], 0);
  EXPECT_EQ(r.clock.calls[CC::kPadForces], 0);
  EXPECT_EQ(r.clock.calls[CC::kVehicleRhs], 0);
}

TEST(CosimTrackCost, RigidFeRunsNoNewmarkWork) {
  const TrackCostRun r = runTrackWithClock(scene("rigid_fe"), false, false);
  EXPECT_EQ(r.newmark_steps, 0);
  EXPECT_EQ(r.clock.calls[CC::kTrackRhs], 0);
  EXPECT_EQ(r.clock.calls[CC::kTrackSolve], 0);
  EXPECT_EQ(r.clock.seconds[CC::kTrackSolve], 0.0);
  EXPECT_EQ(r.clock.counts[CC::kDampingProducts], 0);
  EXPECT_GT(r.clock.contact.evaluations, 0);
}

TEST(CosimTrackCost, TrackDampingOffComputesNoDampingProduct) {
  Scene sc = scene("flexible");
  sc.effects.track_damping = false;
  sc.effects.absorbing_ends = false;  // the end dashpots are the other entries of C
  const TrackCostRun off = runTrackWithClock(sc, false, false);
  ASSERT_EQ(off.newmark_steps, 25);
  EXPECT_EQ(off.clock.counts[CC::kDampingProducts], 0);
  sc.effects.track_damping = true;
  const TrackCostRun on = runTrackWithClock(sc, false, false);
  EXPECT_EQ(on.clock.counts[CC::kDampingProducts], 25);  // one C v product per step
}

TEST(CosimTrackCost, AbsorbingEndsOffComputeNoDashpotForce) {
  Scene sc = scene("flexible");
  sc.effects.absorbing_ends = false;
  const TrackCostRun off = runTrackWithClock(sc, false, false);
  EXPECT_EQ(off.clock.counts[CC::kEndDashpotForces], 0);
  EXPECT_EQ(off.clock.counts[CC::kDampingProducts], 25);  // the track's own damping is still there
  sc.effects.absorbing_ends = true;
  const TrackCostRun on = runTrackWithClock(sc, false, false);
  EXPECT_EQ(on.clock.counts[CC::kEndDashpotForces], 4 * 25);  // a dashpot at each of the 4 rail ends
}

TEST(CosimTrackCost, FlangeContactAndSpinOffCostNothingOnTheTrackSide) {
  Scene sc = scene("flexible");
  sc.effects.flange_contact = false;
  sc.effects.spin_creepage = false;
  const TrackCostRun off = runTrackWithClock(sc, false, false);
  EXPECT_EQ(off.clock.contact.flange_searches, 0);
  EXPECT_EQ(off.clock.contact.flange_detection_seconds, 0.0);
  EXPECT_GT(off.clock.contact.creep_evaluations, 0);
  EXPECT_EQ(off.clock.contact.spin_evaluations, 0);
  sc.effects.flange_contact = true;
  sc.effects.spin_creepage = true;
  const TrackCostRun on = runTrackWithClock(sc, false, false);
  EXPECT_EQ(on.clock.contact.flange_searches, 8 * 26);
  EXPECT_GT(on.clock.contact.flange_detection_seconds, 0.0);
  // Semi-implicit Newton included: every creep evaluation has the spin terms.
  EXPECT_EQ(on.clock.contact.spin_evaluations, on.clock.contact.creep_evaluations);
  EXPECT_GT(on.clock.contact.spin_evaluations, 0);
}

TEST(CosimTrackCost, RailDeflectionAndPadForceOutputsCostOnlyWhenAskedFor) {
  const TrackCostRun off = runTrackWithClock(scene("flexible"), false, false);
  EXPECT_EQ(off.clock.calls[CC::kRailDeflection], 0);
  EXPECT_EQ(off.clock.seconds[CC::kRailDeflection], 0.0);
  EXPECT_EQ(off.clock.calls[CC::kPadForces], 0);
  EXPECT_EQ(off.clock.seconds[CC::kPadForces], 0.0);
  const TrackCostRun on = runTrackWithClock(scene("flexible"), true, true);
  EXPECT_EQ(on.clock.calls[CC::kRailDeflection], 26);
  EXPECT_GT(on.clock.seconds[CC::kRailDeflection], 0.0);
  EXPECT_EQ(on.clock.calls[CC::kPadForces], 26);
  EXPECT_GT(on.clock.seconds[CC::kPadForces], 0.0);
}
