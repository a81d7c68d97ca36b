#include "rail_contact/contact_geometry_table.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "rail_contact/illinois.hpp"

namespace rail {
namespace contact {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

ContactGeometryTable::ContactGeometryTable(const WheelProfile& wheel, const ProfileCurve& rail,
                                           const WheelsetTrackSpec& spec, const WheelContactOptions& options)
    : spec_(spec) {
  auto check = [](const char* field, double v, double lo, double hi) {
    if (!(v > lo) || !(v < hi)) {
      std::ostringstream m;
      m << "WheelsetTrackSpec: " << field << " = " << v << " m is outside (" << lo << ", " << hi << ")";
      throw std::runtime_error(m.str());
    }
  };
  check("track_gauge", spec.track_gauge, 0.3, 3.0);
  check("gauge_depth", spec.gauge_depth, 0.0, 0.05);
  check("back_to_back", spec.back_to_back, 0.2, spec.track_gauge);
  check("nominal_radius", spec.nominal_radius, 0.1, 2.0);
  const Eigen::Vector2d gp = gaugePoint(rail, spec.gauge_depth);
  h_rail_ = 0.5 * spec.track_gauge + gp.x();
  check("taping_line_from_flange_back", spec.taping_line_from_flange_back, 0.0, 0.2);
  e_wheel_ = 0.5 * spec.back_to_back + spec.taping_line_from_flange_back;
  GeometrySpec gs;
  SegmentSpec seg;
  seg.type = SegmentSpec::Type::Straight;
  seg.length = 20.0;
  gs.segments = {seg};
  gs.rail_half_spacing = h_rail_;
  gs.cant_reference_width = 2.0 * h_rail_;
  gs.table_step = 0.5;
  track_ = std::make_unique<TrackGeometry>(gs);
  x0_ = 10.0;
  const Eigen::Vector2d centre =
      spec.rail_section_centre_yz.allFinite() ? spec.rail_section_centre_yz : railSectionCentre(rail);
  // A table row is one contact point per surface (the benchmark's convention) of round wheels.
  WheelContactOptions table_options = options;
  table_options.second_contacts = false;
  table_options.wheel_defects = WheelDefects();
  model_ = std::make_unique<WheelContactModel>(wheel, spec.nominal_radius, rail, centre, table_options);
  rail_top_yz_ = railTopPoint(rail);
  z_guess_ = spec.nominal_radius + rail_top_yz_.y();
  roll_guess_ = 0.0;
}

void ContactGeometryTable::place(double y, double yaw, double z, double roll, double speed, double omega,
                                 WheelState& left, WheelState& right) const {
  const Eigen::Matrix3d R =
      (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  const Eigen::Vector3d c(x0_, y, z);
  for (int k = 0; k < 2; ++k) {
    WheelState& w = k == 0 ? left : right;
    w.R_wheelset_to_world = R;
    w.p_wheel_in_world = c + R * Eigen::Vector3d(0.0, k == 0 ? e_wheel_ : -e_wheel_, 0.0);
    w.arc_length = x0_;
    w.v_wheel_in_world = speed * Eigen::Vector3d::UnitX();
    w.omega_wheelset_in_world = omega * R.col(1);
  }
}

void ContactGeometryTable::detectBoth(double y, double yaw, double z, double roll, ContactGeometry (&left)[2],
                                      ContactGeometry (&right)[2]) {
  WheelState wl, wr;
  place(y, yaw, z, roll, 0.0, 0.0, wl, wr);
  for (int k = 0; k < 2; ++k) {
    const bool is_left = k == 0;
    const WheelState& ws = is_left ? wl : wr;
    WheelPose pose;
    pose.p_wheel_in_world = ws.p_wheel_in_world;
    pose.R_wheelset_to_world = ws.R_wheelset_to_world;
    pose.side = is_left ? RailSide::kLeft : RailSide::kRight;
    pose.arc_length = ws.arc_length;
    ContactGeometry* g = is_left ? left : right;
    for (int surf = 0; surf < 2; ++surf) {
      g[surf] = ContactGeometry();
      if (surf == kFlange && !model_->options().flange_contact) continue;
      // The table needs the global minimum gap: start every detection from the robust search.
      work_[k].detection[surf].has_warm_start = false;
      model_->detector().detect(static_cast<WheelSurface>(surf), pose, *track_, RigidRailDeformation(),
                                work_[k].detection[surf], g[surf]);
    }
  }
}

double ContactGeometryTable::wheelGap(const ContactGeometry* g, int& kind) const {
  kind = -1;
  double gap = std::numeric_limits<double>::infinity();
  for (int s = 0; s < 2; ++s) {
    // A point past a surface's end is the other surface's (taken only when it penetrates): the table's gap
    // is each surface's own nearest point, continuous through zero.
    if (!g[s].valid || g[s].past_end) continue;
    if (-g[s].penetration < gap) {
      gap = -g[s].penetration;
      kind = s;
    }
  }
  return gap;
}

bool ContactGeometryTable::solveRigid(double y, double yaw, double& z, double& roll) {
  z = z_guess_;
  roll = roll_guess_;
  ContactGeometry gl[2], gr[2];
  int kl, kr;
  for (int it = 0; it < 40; ++it) {
    detectBoth(y, yaw, z, roll, gl, gr);
    const Eigen::Vector2d g(wheelGap(gl, kl), wheelGap(gr, kr));
    if (kl < 0 || kr < 0 || !g.allFinite()) return false;
    if (g.cwiseAbs().maxCoeff() < 1e-11) {
      z_guess_ = z;
      roll_guess_ = roll;
      return true;
    }
    const double h = 1e-7;
    Eigen::Matrix2d J;
    detectBoth(y, yaw, z + h, roll, gl, gr);
    J.col(0) = (Eigen::Vector2d(wheelGap(gl, kl), wheelGap(gr, kr)) - g) / h;
    detectBoth(y, yaw, z, roll + h, gl, gr);
    J.col(1) = (Eigen::Vector2d(wheelGap(gl, kl), wheelGap(gr, kr)) - g) / h;
    const Eigen::Vector2d dx = J.fullPivLu().solve(-g);
    if (!dx.allFinite()) return false;
    z += std::clamp(dx[0], -0.005, 0.005);
    roll += std::clamp(dx[1], -0.005, 0.005);
  }
  return false;
}

bool ContactGeometryTable::solveLoaded(double y, double yaw, const LoadCase& load, double& z, double& roll,
                                       double& omega, std::string* why) {
  // Residuals (N): each wheel's vertical force minus Q and, free rolling, the net moment of the contact
  // forces about the axle divided by r0 (zero: no traction or braking torque).
  const double omega_scale = load.speed / spec_.nominal_radius;
  auto residual = [&](double zz, double rr, double ww) {
    WheelState wl, wr;
    place(y, yaw, zz, rr, load.speed, ww, wl, wr);
    WheelContactResult res;
    Eigen::Vector3d f;
    model_->evaluate(wl, RailSide::kLeft, *track_, RigidRailDeformation(), work_[0], res);
    f[0] = res.wheel_centre.force_in_world.z() - load.wheel_load;
    f[2] = res.wheel_centre.moment_in_wheelset.y();
    model_->evaluate(wr, RailSide::kRight, *track_, RigidRailDeformation(), work_[1], res);
    f[1] = res.wheel_centre.force_in_world.z() - load.wheel_load;
    f[2] = (f[2] + res.wheel_centre.moment_in_wheelset.y()) / spec_.nominal_radius;
    return f;
  };
  const bool solve_omega = load.free_rolling && omega_scale > 0.0;
  omega = omega_scale;
  z -= 5e-5;  // start inside the rails: the Hertz force has zero slope at zero penetration
  auto value = [&](double zz, double rr, double ww) {
    Eigen::Vector3d f = residual(zz, rr, ww);
    if (!solve_omega) f[2] = 0.0;
    return f;
  };
  const double z0 = z, roll0 = roll;
  for (int it = 0; it < 80; ++it) {
    const Eigen::Vector3d f = value(z, roll, omega);
    if (!f.allFinite()) break;
    if (f.cwiseAbs().maxCoeff() < 1e-6 * load.wheel_load) return true;
    const double hz = 1e-8, hw = 1e-7 * omega_scale;
    Eigen::Matrix3d J = Eigen::Matrix3d::Identity();
    J.col(0) = (value(z + hz, roll, omega) - f) / hz;
    J.col(1) = (value(z, roll + hz, omega) - f) / hz;
    if (solve_omega) {
      J.col(2) = (value(z, roll, omega + hw) - f) / hw;
    } else {
      J.row(2).setZero();
      J.col(2).setZero();
      J(2, 2) = 1.0;
    }
    const Eigen::Vector3d dx = J.fullPivLu().solve(-f);
    if (!dx.allFinite()) break;
    z += std::clamp(dx[0], -2e-5, 2e-5);
    roll += std::clamp(dx[1], -2e-5, 2e-5);
    if (solve_omega) omega += std::clamp(dx[2], -2e-3 * omega_scale, 2e-3 * omega_scale);
  }

  // Fallback where Newton stalls (a wheel's load passing between tread and flange puts a kink in the
  // forces): nested bracketing on functions monotonic in their own unknown. Outer: roll, for the left
  // wheel's share of the load; middle: height, for the total load; inner: pitch rate, for no torque. The
  // brackets (roll +-2 mrad, height -1.5..+3 mm of the rigid solution, pitch rate +-3 %) keep every
  // penetration below the detection's 5 mm limit.
  // jump_out: where the bracket closes on a jump of g instead of a root, the jump's size.
  auto solve1d = [](auto&& g, double lo, double hi, double tol, double& x, double* jump_out = nullptr) {
    IllinoisBracket br{lo, g(lo), hi, g(hi)};
    if (!std::isfinite(br.g_a) || !std::isfinite(br.g_b) || br.g_a * br.g_b > 0.0) return false;
    for (int k = 0; k < 200; ++k) {
      x = br.next();
      if (!(x > std::min(br.a, br.b) && x < std::max(br.a, br.b))) x = 0.5 * (br.a + br.b);
      const double gx = g(x);
      if (!std::isfinite(gx)) return false;
      if (std::abs(gx) < tol) return true;
      if (std::abs(br.b - br.a) < 1e-12 * std::max(1.0, std::abs(x))) {
        if (jump_out) *jump_out = std::max(*jump_out, std::abs(gx));
        return false;
      }
      br.update(x, gx);
    }
    return false;
  };
  const double tol = 1e-6 * load.wheel_load;
  double w_sol = omega_scale, z_sol = z0, jump = 0.0;
  auto omega_for = [&](double zz, double rr) {
    if (!solve_omega) return omega_scale;
    double w = omega_scale;
    const bool ok = solve1d([&](double ww) { return residual(zz, rr, ww)[2]; }, 0.97 * omega_scale, 1.03 * omega_scale,
                            tol, w, &jump);
    return ok ? w : std::numeric_limits<double>::quiet_NaN();
  };
  auto z_for = [&](double rr) {
    double zz = z0;
    const bool ok = solve1d(
        [&](double zt) {
          w_sol = omega_for(zt, rr);
          if (!std::isfinite(w_sol)) return std::numeric_limits<double>::quiet_NaN();
          const Eigen::Vector3d f = residual(zt, rr, w_sol);
          return f[0] + f[1];
        },
        z0 - 1.5e-3, z0 + 3e-3, tol, zz, &jump);
    return ok ? zz : std::numeric_limits<double>::quiet_NaN();
  };
  double roll_sol = roll0;
  const bool ok = solve1d(
      [&](double rr) {
        z_sol = z_for(rr);
        if (!std::isfinite(z_sol) || !std::isfinite(w_sol)) return std::numeric_limits<double>::quiet_NaN();
        const Eigen::Vector3d f = residual(z_sol, rr, w_sol);
        return f[0] - f[1];
      },
      roll0 - 2e-3, roll0 + 2e-3, tol, roll_sol, &jump);
  if (!ok) {
    if (jump > 0.0 && why) {
      std::ostringstream m;
      m << "the wheel loads have no balance at this shift: a contact force jumps by at least "
        << std::lround(jump / 1e3) << " kN where its contact point jumps between two places on the profiles "
        << "(the flange onset: two-point contact, which one point per wheel surface cannot share)";
      *why = m.str();
    }
    return false;
  }
  z_sol = z_for(roll_sol);
  const Eigen::Vector3d f = value(z_sol, roll_sol, w_sol);
  if (!(f.allFinite() && f.cwiseAbs().maxCoeff() < 1e-5 * load.wheel_load)) return false;
  z = z_sol;
  roll = roll_sol;
  omega = w_sol;
  return true;
}

ContactGeometryRow ContactGeometryTable::row(double y, double yaw, const LoadCase& load) {
  ContactGeometryRow r;
  r.y = y;
  r.yaw = yaw;
  r.z_loaded = r.roll_loaded = r.pitch_rate = kNaN;
  double z, roll;
  if (!solveRigid(y, yaw, z, roll)) {
    r.z = r.roll = r.delta_r = kNaN;
    // Say which wheel found no contact point at the last position tried.
    ContactGeometry gl[2], gr[2];
    detectBoth(y, yaw, z_guess_, roll_guess_, gl, gr);
    int kl, kr;
    wheelGap(gl, kl);
    wheelGap(gr, kr);
    if (kl < 0 && kr < 0)
      r.failure = "no contact point found on either wheel (tread and flange)";
    else if (kl < 0)
      r.failure = "no contact point found on the left wheel (tread and flange)";
    else if (kr < 0)
      r.failure = "no contact point found on the right wheel (tread and flange)";
    else
      r.failure = "the rigid position solve (height and roll for zero gap on both wheels) did not converge";
    return r;
  }
  r.ok = true;
  r.z = z;
  r.roll = roll;
  ContactGeometry gl[2], gr[2];
  detectBoth(y, yaw, z, roll, gl, gr);
  WheelState wl, wr;
  place(y, yaw, z, roll, 0.0, 0.0, wl, wr);
  for (int k = 0; k < 2; ++k) {
    const ContactGeometry* g = k == 0 ? gl : gr;
    ContactGeometryWheel& w = k == 0 ? r.left : r.right;
    int kind;
    wheelGap(g, kind);
    w.kind = kind;
    w.flange_gap = g[kFlange].valid ? -g[kFlange].penetration : kNaN;
    if (kind < 0) continue;
    const ContactGeometry& c = g[kind];
    w.y_wheel = c.wheel_y;
    w.z_wheel = c.wheel_z;
    w.y_rail = c.rail_y;
    w.z_rail = c.rail_z;
    w.y_rail_from_top = c.rail_y - rail_top_yz_.x();
    w.rolling_radius = c.wheel_radius;
    const Eigen::Vector3d axle = (k == 0 ? wl : wr).R_wheelset_to_world.col(1);
    w.contact_angle = std::asin(std::clamp(c.n_in_world.dot((k == 0 ? -1.0 : 1.0) * axle), -1.0, 1.0));
  }
  r.delta_r = r.left.rolling_radius - r.right.rolling_radius;
  if (load.wheel_load > 0.0 && load.speed >= 0.0) {
    double zl = z, rl = roll, omega = 0.0;
    std::string why;
    if (!solveLoaded(y, yaw, load, zl, rl, omega, &why)) {
      for (ContactGeometryWheel* w : {&r.left, &r.right})
        w->N = w->a = w->b = w->nu_x = w->nu_y = w->phi = w->F_long = w->F_lat = kNaN;
      r.failure =
          !why.empty() ? why
          : load.free_rolling
              ? "the loaded solve (height, roll and free-rolling pitch rate for the wheel load) did not converge"
              : "the loaded solve (height and roll for the wheel load) did not converge";
      return r;
    }
    r.loaded_ok = true;
    r.z_loaded = zl;
    r.roll_loaded = rl;
    r.pitch_rate = omega;
    WheelState sl, sr;
    place(y, yaw, zl, rl, load.speed, omega, sl, sr);
    for (int k = 0; k < 2; ++k) {
      WheelContactResult res;
      model_->evaluate(k == 0 ? sl : sr, k == 0 ? RailSide::kLeft : RailSide::kRight, *track_, RigidRailDeformation(),
                       work_[k], res);
      ContactGeometryWheel& w = k == 0 ? r.left : r.right;
      const int kind = w.kind >= 0 ? w.kind : 0;
      const ContactPointResult& c = res.contact[res.contact[kind].active ? kind : 1 - kind];
      w.N = c.N;
      w.a = c.a;
      w.b = c.b;
      w.nu_x = c.nu_x;
      w.nu_y = c.nu_y;
      w.phi = c.phi;
      w.F_long = c.F_long;
      w.F_lat = c.F_lat;
    }
  }
  return r;
}

std::vector<ContactGeometryRow> ContactGeometryTable::table(double y_min, double y_max, double dy, double yaw,
                                                            const LoadCase& load, double yaw_per_y) {
  if (!(dy > 0.0) || !(y_max >= y_min)) {
    std::ostringstream m;
    m << "ContactGeometryTable::table: need dy > 0 and y_max >= y_min (dy = " << dy << ", y_min = " << y_min
      << ", y_max = " << y_max << ")";
    throw std::runtime_error(m.str());
  }
  std::vector<ContactGeometryRow> rows;
  const int n = static_cast<int>(std::floor((y_max - y_min) / dy + 1e-9)) + 1;
  auto yaw_at = [&](double y) { return yaw + yaw_per_y * y; };
  // Continuation from the centre outwards keeps the solver on the physical branch.
  rows.resize(n);
  const int i0 = std::clamp(static_cast<int>(std::lround(-y_min / dy)), 0, n - 1);
  for (int pass = 0; pass < 2; ++pass) {
    z_guess_ = model_->detector().nominalRadius();
    roll_guess_ = 0.0;
    const double y0 = y_min + i0 * dy;
    const double zt = row(y0, yaw_at(y0)).z;  // re-centre the guess
    if (std::isfinite(zt)) z_guess_ = zt;
    if (pass == 0)
      for (int i = i0; i < n; ++i) rows[i] = row(y_min + i * dy, yaw_at(y_min + i * dy), load);
    else
      for (int i = i0 - 1; i >= 0; --i) rows[i] = row(y_min + i * dy, yaw_at(y_min + i * dy), load);
  }
  return rows;
}

double ContactGeometryTable::contactHalfDistance() {
  ContactGeometryRow r = row(0.0);
  if (!r.ok) return kNaN;
  ContactGeometry gl[2], gr[2];
  detectBoth(0.0, 0.0, r.z, r.roll, gl, gr);
  int kl, kr;
  wheelGap(gl, kl);
  wheelGap(gr, kr);
  if (kl < 0 || kr < 0) return kNaN;
  return 0.5 * (gl[kl].p_rail_in_world.y() - gr[kr].p_rail_in_world.y());
}

double equivalentConicity(const std::vector<double>& y_table, const std::vector<double>& dr_table, double amplitude,
                          double e0, double r0, double* wavelength_out) {
  if (wavelength_out) *wavelength_out = kNaN;
  const std::size_t n = y_table.size();
  if (n < 2 || dr_table.size() != n || !(amplitude > 0.0) || !(e0 > 0.0) || !(r0 > 0.0)) return kNaN;
  if (amplitude > y_table.back() || -amplitude < y_table.front()) return kNaN;
  auto dr = [&](double y) {
    if (y <= y_table.front()) return dr_table.front();
    if (y >= y_table.back()) return dr_table.back();
    const std::size_t k = std::upper_bound(y_table.begin(), y_table.end(), y) - y_table.begin() - 1;
    const double t = (y - y_table[k]) / (y_table[k + 1] - y_table[k]);
    return (1 - t) * dr_table[k] + t * dr_table[k + 1];
  };
  const double c = 1.0 / (2.0 * e0 * r0);
  auto acc = [&](double y) { return -c * dr(y); };
  // RK4 in x; the step resolves the linearised wavelength of the steepest table slope.
  double slope = 0.0;
  for (std::size_t k = 0; k + 1 < n; ++k)
    slope = std::max(slope, std::abs((dr_table[k + 1] - dr_table[k]) / (y_table[k + 1] - y_table[k])));
  if (!(slope > 0.0)) return kNaN;
  const double lambda_min = 2.0 * M_PI / std::sqrt(c * slope);
  const double h = lambda_min / 4000.0;
  double x = 0.0, y = amplitude, v = 0.0;
  int zero_crossings = 0;
  const double x_max = 1e4 * lambda_min;
  while (x < x_max) {
    const double k1y = v, k1v = acc(y);
    const double k2y = v + 0.5 * h * k1v, k2v = acc(y + 0.5 * h * k1y);
    const double k3y = v + 0.5 * h * k2v, k3v = acc(y + 0.5 * h * k2y);
    const double k4y = v + h * k3v, k4v = acc(y + h * k3y);
    const double y1 = y + h / 6.0 * (k1y + 2 * k2y + 2 * k3y + k4y);
    const double v1 = v + h / 6.0 * (k1v + 2 * k2v + 2 * k3v + k4v);
    // Turning points: v changes sign. The second one after the start closes one wavelength.
    if ((v < 0.0 && v1 >= 0.0) || (v > 0.0 && v1 <= 0.0)) {
      ++zero_crossings;
      if (zero_crossings == 2) {
        const double x_cross = x + h * v / (v - v1);
        if (wavelength_out) *wavelength_out = x_cross;
        return e0 * r0 * std::pow(2.0 * M_PI / x_cross, 2);
      }
    }
    x += h;
    y = y1;
    v = v1;
  }
  return kNaN;
}

int writeContactGeometryCsv(const std::string& path, const std::vector<ContactGeometryRow>& rows) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error(path + ": cannot open for writing");
  f << "y_m,yaw_rad,z_m,roll_rad,delta_r_m,z_loaded_m,roll_loaded_rad,pitch_rate_rad_s";
  for (const char* s : {"left", "right"})
    f << ',' << s << "_kind," << s << "_y_wheel_m," << s << "_z_wheel_m," << s << "_y_rail_m," << s << "_z_rail_m," << s
      << "_y_rail_from_top_m," << s << "_contact_angle_rad," << s << "_rolling_radius_m," << s << "_flange_gap_m," << s
      << "_N_N," << s << "_a_m," << s << "_b_m," << s << "_nu_x," << s << "_nu_y," << s << "_phi_1pm," << s
      << "_F_long_N," << s << "_F_lat_N";
  f << '\n' << std::setprecision(10);
  int written = 0;
  for (const ContactGeometryRow& r : rows) {
    if (!r.ok) continue;
    ++written;
    f << r.y << ',' << r.yaw << ',' << r.z << ',' << r.roll << ',' << r.delta_r << ',' << r.z_loaded << ','
      << r.roll_loaded << ',' << r.pitch_rate;
    for (const ContactGeometryWheel* w : {&r.left, &r.right})
      f << ','
        << (w->kind == 0   ? "tread"
            : w->kind == 1 ? "flange"
                           : "none")
        << ',' << w->y_wheel << ',' << w->z_wheel << ',' << w->y_rail << ',' << w->z_rail << ',' << w->y_rail_from_top
        << ',' << w->contact_angle << ',' << w->rolling_radius << ',' << w->flange_gap << ',' << w->N << ',' << w->a
        << ',' << w->b << ',' << w->nu_x << ',' << w->nu_y << ',' << w->phi << ',' << w->F_long << ',' << w->F_lat;
    f << '\n';
  }
  f.close();
  if (!f) throw std::runtime_error(path + ": write failed");
  return written;
}

}  // namespace contact
}  // namespace rail
