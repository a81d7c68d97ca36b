// contact_geometry: writes the contact-geometry table of a wheelset on straight rigid track as CSV, and
// the equivalent conicity against amplitude (EN 15302 principle) as a second CSV.
//
// Usage: contact_geometry --out table.csv [--conicity conicity.csv] [--wheel FILE] [--rail FILE]
//          [--gauge 1.435] [--back-to-back 1.360] [--radius 0.46] [--inclination 0.025]
//          [--y-max 0.010] [--dy 0.0001] [--yaw 0] [--load Q_N] [--speed V_mps] [--friction 0.3]
// Without --wheel / --rail: S1002 and UIC60 (inclined by --inclination, tan of the cant angle). SI units.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

#include "rail_contact/contact_geometry_table.hpp"

namespace rc = rail::contact;

int main(int argc, char** argv) {
  std::string out = "contact_geometry.csv", conicity_out, wheel_file, rail_file;
  double gauge = 1.435, b2b = 1.360, radius = 0.46, incl = 1.0 / 40.0, y_max = 0.010, dy = 1e-4, yaw = 0.0;
  double load = 0.0, speed = 0.0, friction = 0.3;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "contact_geometry: %s needs a value\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    auto num = [&]() {
      const std::string v = next();
      char* end = nullptr;
      const double x = std::strtod(v.c_str(), &end);
      if (end == v.c_str() || *end != '\0' || !std::isfinite(x)) {
        std::fprintf(stderr, "contact_geometry: %s: not a number (%s)\n", a.c_str(), v.c_str());
        std::exit(2);
      }
      return x;
    };
    if (a == "--out") out = next();
    else if (a == "--conicity") conicity_out = next();
    else if (a == "--wheel") wheel_file = next();
    else if (a == "--rail") rail_file = next();
    else if (a == "--gauge") gauge = num();
    else if (a == "--back-to-back") b2b = num();
    else if (a == "--radius") radius = num();
    else if (a == "--inclination") incl = num();
    else if (a == "--y-max") y_max = num();
    else if (a == "--dy") dy = num();
    else if (a == "--yaw") yaw = num();
    else if (a == "--load") load = num();
    else if (a == "--speed") speed = num();
    else if (a == "--friction") friction = num();
    else {
      std::fprintf(stderr, "contact_geometry: unknown option %s (see the header of contact_geometry_main.cpp)\n", a.c_str());
      return 2;
    }
  }
  try {
    const rc::WheelProfile wheel = wheel_file.empty() ? rc::makeS1002() : rc::loadWheelProfile(wheel_file);
    rc::ProfileCurve rail;
    if (rail_file.empty()) {
      rail = rc::makeUic60Rail(incl);
    } else {
      rail = rc::ProfileCurve(rc::tiltProfile(rc::readProfilePoints(rail_file), incl), rc::SolidSide::Right);
    }
    rc::WheelsetTrackSpec spec;
    spec.track_gauge = gauge;
    spec.back_to_back = b2b;
    spec.nominal_radius = radius;
    rc::WheelContactOptions options;
    options.friction = friction;
    rc::ContactGeometryTable table(wheel, rail, spec, options);
    rc::LoadCase lc;
    lc.wheel_load = load;
    lc.speed = speed;
    const std::vector<rc::ContactGeometryRow> rows = table.table(-y_max, y_max, dy, yaw, lc);
    rc::writeContactGeometryCsv(out, rows);
    std::printf("wrote %s (%zu rows)\n", out.c_str(), rows.size());
    if (!conicity_out.empty()) {
      std::vector<double> y, dr;
      for (const rc::ContactGeometryRow& r : rows)
        if (r.ok) {
          y.push_back(r.y);
          dr.push_back(r.delta_r);
        }
      const double e0 = table.contactHalfDistance();
      std::ofstream f(conicity_out);
      if (!f) throw std::runtime_error(conicity_out + ": cannot open for writing");
      f << "amplitude_m,equivalent_conicity,wavelength_m,e0_m,r0_m\n";
      for (double A = 0.0005; A <= 0.98 * y_max + 1e-12; A += 0.0005) {
        double lambda;
        const double g = rc::equivalentConicity(y, dr, A, e0, radius, &lambda);
        f << A << ',' << g << ',' << lambda << ',' << e0 << ',' << radius << '\n';
      }
      double l3;
      std::printf("wrote %s; equivalent conicity at 3 mm: %.4f (e0 = %.4f m)\n", conicity_out.c_str(),
                  rc::equivalentConicity(y, dr, 0.003, e0, radius, &l3), e0);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "contact_geometry: %s\n", e.what());
    return 1;
  }
  return 0;
}
