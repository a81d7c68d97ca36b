// Benchmark of the per-wheel contact evaluation (prints figures; not a test): a wheelset rolling on
// straight rigid track (S1002 / UIC60 1:40) with a lateral oscillation of 4 mm amplitude and a small yaw,
// warm-started detection; time per wheel for detection alone and for detection + forces, with tread +
// flange on both rails, then with flange contact and spin off; fallback counts.
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "rail_contact/contact_geometry_table.hpp"
#include "rail_contact/tool_args.hpp"

namespace rc = rail::contact;

namespace {
void run(bool flange, bool spin) {
  rc::WheelContactOptions o;
  o.flange_contact = flange;
  o.spin = spin;
  rc::ContactGeometryTable table(rc::makeS1002(), rc::makeUic60Rail(1.0 / 40.0), rc::WheelsetTrackSpec(), o);
  const rc::WheelContactModel& model = table.model();
  const int n = 20000;
  // Precompute poses (height and roll from the table, 20 um into the rails).
  std::vector<rc::WheelState> states(2 * n);
  std::vector<rc::ContactGeometryRow> rows;
  for (int i = 0; i <= 80; ++i) rows.push_back(table.row(-0.004 + i * 1e-4));
  for (int i = 0; i < n; ++i) {
    const double y = 0.004 * std::sin(2.0 * M_PI * i / 4000.0);
    const rc::ContactGeometryRow& r = rows[static_cast<int>(std::lround((y + 0.004) / 1e-4))];
    const Eigen::Matrix3d R = (Eigen::AngleAxisd(1e-3 * std::cos(2.0 * M_PI * i / 4000.0), Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(r.roll, Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
    for (int k = 0; k < 2; ++k) {
      rc::WheelState& w = states[2 * i + k];
      w.R_wheelset_to_world = R;
      w.p_wheel_in_world =
          Eigen::Vector3d(2.0 + 0.8e-3 * i, y, r.z - 20e-6) +
          R * Eigen::Vector3d(0.0, k == 0 ? table.wheelHalfDistance() : -table.wheelHalfDistance(), 0.0);
      w.v_wheel_in_world = Eigen::Vector3d(40.0, 0.0, 0.0);
      w.omega_wheelset_in_world = (40.0 / 0.46) * R.col(1);
      w.arc_length = w.p_wheel_in_world.x();
    }
  }
  // Detection only.
  rc::WheelContactWork work[2];
  rc::ContactGeometry g;
  auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 2; ++k) {
      const rc::WheelState& w = states[2 * i + k];
      rc::WheelPose p;
      p.p_wheel_in_world = w.p_wheel_in_world;
      p.R_wheelset_to_world = w.R_wheelset_to_world;
      p.side = k == 0 ? rc::RailSide::kLeft : rc::RailSide::kRight;
      p.arc_length = w.arc_length;
      for (int s = 0; s < (flange ? 2 : 1); ++s)
        model.detector().detect(static_cast<rc::WheelSurface>(s), p, table.track(), rc::RigidRailDeformation(),
                                work[k].detection[s], g);
    }
  auto t1 = std::chrono::steady_clock::now();
  // Detection + forces.
  rc::WheelContactWork work2[2];
  rc::WheelContactResult out;
  double checksum = 0.0;
  auto t2 = std::chrono::steady_clock::now();
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < 2; ++k) {
      model.evaluate(states[2 * i + k], k == 0 ? rc::RailSide::kLeft : rc::RailSide::kRight, table.track(),
                     rc::RigidRailDeformation(), work2[k], out);
      checksum += out.wheel_centre.force_in_world.z();
    }
  auto t3 = std::chrono::steady_clock::now();
  const double us_det = std::chrono::duration<double, std::micro>(t1 - t0).count() / (2.0 * n);
  const double us_all = std::chrono::duration<double, std::micro>(t3 - t2).count() / (2.0 * n);
  long long fb = 0, se = 0, ap = 0, it = 0, calls = 0;
  for (int k = 0; k < 2; ++k)
    for (int s = 0; s < 2; ++s) {
      fb += work2[k].detection[s].fallbacks;
      se += work2[k].detection[s].searches;
      ap += work2[k].detection[s].approximations;
      it += work2[k].detection[s].newton_iterations;
      calls += work2[k].detection[s].calls;
    }
  std::printf(
      "flange %-3s spin %-3s: detection %.2f us/wheel, detection+forces %.2f us/wheel; "
      "%lld detections, %.2f Newton it/detection, %lld searches (%lld fallbacks), %lld approximate "
      "(mean Fz %.0f N)\n",
      flange ? "on" : "off", spin ? "on" : "off", us_det, us_all, calls, double(it) / calls, se, fb, ap,
      checksum / (2.0 * n));
}
}  // namespace

int main(int argc, char** argv) {
  const char* const usage =
      "usage: bench_contact\n"
      "Per-wheel contact evaluation on straight rigid track (S1002 / UIC60 1:40, 4 mm lateral oscillation):\n"
      "time per wheel for detection alone and with forces, tread + flange, then flange and spin off.\n";
  if (rail::tools::startTool(argc, argv, usage, 0)) return 0;
  run(true, true);
  run(false, false);
  return 0;
}
