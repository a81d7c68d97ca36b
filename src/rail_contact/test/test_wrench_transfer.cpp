// Tests of the transfer of contact forces to wheel, wheelset and rail section (eqs. 13-15):
// an equivalent force system must reproduce the total force and the moment of the original
// forces about any point. Tolerances 1e-12 relative to |r||f|: the two sides differ only by
// rounding of a handful of cross products and rotations.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "rail_contact/wrench_transfer.hpp"

namespace rc = rail::contact;
using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace {

struct Rng {
  std::mt19937 gen{12345u};
  std::uniform_real_distribution<double> u{-1.0, 1.0};
  Vector3d vec(double scale) { return Vector3d(u(gen), u(gen), u(gen)) * scale; }
  Matrix3d rot() { return Eigen::AngleAxisd(3.0 * u(gen), vec(1.0).normalized()).toRotationMatrix(); }
};

void expectVecNear(const Vector3d& a, const Vector3d& b, double tol) {
  EXPECT_NEAR((a - b).norm(), 0.0, tol) << "a=" << a.transpose() << " b=" << b.transpose();
}

}  // namespace

// Eq. 13 and eq. 14 for both wheels of a wheelset: the resultant at the wheelset centre has
// the same total force and the same moment about an arbitrary point P as the four contact
// forces (two per wheel: tread and flange).
TEST(WrenchTransfer, WheelsetEquivalentForceSystem) {
  Rng rng;
  for (int trial = 0; trial < 50; ++trial) {
    const Matrix3d A_ws = rng.rot();       // wheelset body -> world
    const Vector3d r_ws = rng.vec(100.0);  // wheelset centre, world
    const Vector3d P = rng.vec(100.0);     // arbitrary point, world
    rc::WheelsetWrench total;
    Vector3d F_ref = Vector3d::Zero(), M_ref_about_P = Vector3d::Zero();
    for (int side = 0; side < 2; ++side) {
      const Vector3d s_w = Vector3d(0.0, side ? -0.75 : 0.75, 0.0) + rng.vec(0.01);  // wheel centre, body
      const Vector3d s_tr = rng.vec(0.5), s_fl = rng.vec(0.5);  // contact points from wheel centre, body
      const Vector3d f_tr = rng.vec(1e5), f_fl = rng.vec(5e4);  // forces on wheel, world
      const rc::WheelsetWrench wheel = rc::wheelCentreWrench(f_tr, f_fl, s_tr, s_fl, A_ws);
      rc::accumulate(total, rc::wheelsetCentreWrench(wheel, s_w, A_ws));
      // Reference: each force at its world application point.
      const Vector3d r_tr = r_ws + A_ws * (s_w + s_tr);
      const Vector3d r_fl = r_ws + A_ws * (s_w + s_fl);
      F_ref += f_tr + f_fl;
      M_ref_about_P += (r_tr - P).cross(f_tr) + (r_fl - P).cross(f_fl);
    }
    const double scale = 1e5 * 200.0;
    expectVecNear(total.force_in_world, F_ref, 1e-12 * 1e5);
    const Vector3d M_eq_about_P = A_ws * total.moment_in_wheelset + (r_ws - P).cross(total.force_in_world);
    expectVecNear(M_eq_about_P, M_ref_about_P, 1e-12 * scale);
  }
}

// Eq. 13 alone: moment about the wheel centre, expressed in the wheelset frame.
TEST(WrenchTransfer, WheelCentreMomentInBodyFrame) {
  Rng rng;
  const Matrix3d A_ws = rng.rot();
  const Vector3d s_tr(0.01, 0.02, -0.46), s_fl(0.0, -0.03, -0.47);
  const Vector3d f_tr(1e3, 2e3, 8e4), f_fl(0.0, -3e4, 1e4);
  const rc::WheelsetWrench w = rc::wheelCentreWrench(f_tr, f_fl, s_tr, s_fl, A_ws);
  const Vector3d M_world = (A_ws * s_tr).cross(f_tr) + (A_ws * s_fl).cross(f_fl);
  expectVecNear(A_ws * w.moment_in_wheelset, M_world, 1e-12 * 1e5);
  // Inactive flange: passing a zero force leaves only the tread contribution.
  const rc::WheelsetWrench t = rc::wheelCentreWrench(f_tr, Vector3d::Zero(), s_tr, s_fl, A_ws);
  expectVecNear(A_ws * t.moment_in_wheelset, (A_ws * s_tr).cross(f_tr), 1e-12 * 1e5);
}

// Eq. 15 on the rail: forces on the rail (opposite to the wheel forces) at the contact points,
// offsets given in cross-section coordinates and rotated by A_r. The section-centre wrench has
// the same resultant and moment about an arbitrary point. Also: wheel and rail wrenches about
// a common point cancel (action = reaction).
TEST(WrenchTransfer, RailSectionEquivalentForceSystem) {
  Rng rng;
  for (int trial = 0; trial < 50; ++trial) {
    const Matrix3d A_r = rng.rot();
    const Vector3d r_sec = rng.vec(500.0), P = rng.vec(500.0);
    const Vector3d s_tr_sec = rng.vec(0.05), s_fl_sec = rng.vec(0.05);
    const Vector3d f_tr_wheel = rng.vec(1e5), f_fl_wheel = rng.vec(5e4);
    const Vector3d s_tr = rc::sectionOffsetToWorld(A_r, s_tr_sec);
    const Vector3d s_fl = rc::sectionOffsetToWorld(A_r, s_fl_sec);
    const rc::RailWrench w = rc::railSectionWrench(-f_tr_wheel, -f_fl_wheel, s_tr, s_fl);
    const Vector3d M_ref = (r_sec + s_tr - P).cross(-f_tr_wheel) + (r_sec + s_fl - P).cross(-f_fl_wheel);
    expectVecNear(w.force_in_world, -(f_tr_wheel + f_fl_wheel), 1e-12 * 1e5);
    expectVecNear(w.moment_in_world + (r_sec - P).cross(w.force_in_world), M_ref, 1e-12 * 1e5 * 1000.0);
    // Wheel side of the same contacts, wheel centre chosen at the section centre + offset.
    const Matrix3d A_ws = rng.rot();
    const Vector3d r_wc = r_sec + rng.vec(0.5);
    const rc::WheelsetWrench ww =
        rc::wheelCentreWrench(f_tr_wheel, f_fl_wheel, A_ws.transpose() * (r_sec + s_tr - r_wc),
                              A_ws.transpose() * (r_sec + s_fl - r_wc), A_ws);
    const Vector3d M_wheel_about_P = A_ws * ww.moment_in_wheelset + (r_wc - P).cross(ww.force_in_world);
    const Vector3d M_rail_about_P = w.moment_in_world + (r_sec - P).cross(w.force_in_world);
    expectVecNear(M_wheel_about_P + M_rail_about_P, Vector3d::Zero(), 1e-12 * 1e5 * 1000.0);
  }
}

// Eq. 12: f = N n + F_long t_w + F_lat t_u.
TEST(WrenchTransfer, ContactForceComposition) {
  Rng rng;
  const Matrix3d R = rng.rot();
  const Vector3d f = rc::contactForceInWorld(R, 1.0e3, -2.0e3, 8.0e4);
  expectVecNear(f, 8.0e4 * R.col(2) + 1.0e3 * R.col(0) - 2.0e3 * R.col(1), 1e-10);
}
