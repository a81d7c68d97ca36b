// contact_geometry: writes the contact-geometry table of a wheelset on straight rigid track as CSV, and
// the equivalent conicity against amplitude (EN 15302 principle) as a second CSV. `--help` lists the
// options. Rows that cannot be solved are listed on stderr with the reason; a table with no solved row
// exits 1.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

#include "rail_contact/contact_geometry_table.hpp"
#include "rail_contact/tool_args.hpp"

namespace rc = rail::contact;

namespace {

const char* const kUsage =
    "usage: contact_geometry --out table.csv [options]\n"
    "\n"
    "Contact-geometry table of a wheelset on straight rigid track: for each lateral displacement y the\n"
    "contact points on wheel and rail, contact angles, rolling radii and their difference; with --load\n"
    "also the loaded wheelset (each wheel carries the load vertically, rolling freely about its axle):\n"
    "normal loads, ellipses, creepages and creep forces. SI units; y > 0 moves the wheelset to the left.\n"
    "\n"
    "options:\n"
    "  --out FILE            table CSV (default contact_geometry.csv)\n"
    "  --conicity FILE       equivalent conicity against amplitude (EN 15302 principle) as CSV\n"
    "  --wheel FILE          wheel profile (.prw SIMPACK, .whl MiniProf, plain 'y z'); default S1002\n"
    "  --rail FILE           rail profile (.prr, .ban, plain); default UIC60 tilted by --inclination\n"
    "  --inclination I       tan of the rail cant applied to the rail (default 0.025 = 1:40; 0 for a\n"
    "                        file whose profile is inclined already)\n"
    "  --gauge G             track gauge, m, at 14 mm below the rail top (default 1.435)\n"
    "  --back-to-back B      distance between the flange back faces, m (default 1.360)\n"
    "  --taping-line D       flange back face to taping line, m (default 0.070)\n"
    "  --radius R0           nominal rolling radius, m (default 0.46)\n"
    "  --y-min Y, --y-max Y  lateral displacement range, m (default -y_max .. 0.010)\n"
    "  --dy DY               step, m (default 0.0001)\n"
    "  --yaw PSI             yaw angle, rad (default 0)\n"
    "  --yaw-per-shift K     yaw grows with the displacement: yaw = PSI + K y, rad/m (default 0)\n"
    "  --load Q              vertical load per wheel, N (loaded columns; needs --speed)\n"
    "  --speed V             forward speed, m/s\n"
    "  --fixed-spin          pitch rate fixed at V / R0 instead of free rolling\n"
    "  --friction MU         friction coefficient (default 0.3)\n"
    "  -h, --help            this text\n"
    "\n"
    "Rows that cannot be solved are left out and listed on stderr with the reason; a row whose loaded\n"
    "solve fails keeps its geometry with the loaded columns empty (NaN), listed the same way.\n"
    "exit status: 0 table written (every row left out or incomplete listed on stderr);\n"
    "1 no row solved or bad data; 2 bad option.\n";

}  // namespace

int main(int argc, char** argv) {
  if (rail::tools::startTool(argc, argv, kUsage, rail::tools::kOwnOptions)) return 0;
  std::string out = "contact_geometry.csv", conicity_out, wheel_file, rail_file;
  double gauge = 1.435, b2b = 1.360, taping = rc::kTapingLineFromFlangeBack, radius = 0.46, incl = 1.0 / 40.0;
  double y_max = 0.010, dy = 1e-4, yaw = 0.0, yaw_per_y = 0.0;
  double y_min = std::nan("");
  double load = 0.0, speed = 0.0, friction = 0.3;
  bool fixed_spin = false;
  rail::tools::Options o(argc, argv, "contact_geometry");
  while (o.next()) {
    if (o.is("--out"))
      out = o.value();
    else if (o.is("--conicity"))
      conicity_out = o.value();
    else if (o.is("--wheel"))
      wheel_file = o.value();
    else if (o.is("--rail"))
      rail_file = o.value();
    else if (o.is("--gauge"))
      gauge = o.number();
    else if (o.is("--back-to-back"))
      b2b = o.number();
    else if (o.is("--taping-line"))
      taping = o.number();
    else if (o.is("--radius"))
      radius = o.number();
    else if (o.is("--inclination"))
      incl = o.number();
    else if (o.is("--y-min"))
      y_min = o.number();
    else if (o.is("--y-max"))
      y_max = o.number();
    else if (o.is("--dy"))
      dy = o.number();
    else if (o.is("--yaw"))
      yaw = o.number();
    else if (o.is("--yaw-per-shift"))
      yaw_per_y = o.number();
    else if (o.is("--load"))
      load = o.number();
    else if (o.is("--speed"))
      speed = o.number();
    else if (o.is("--fixed-spin"))
      fixed_spin = true;
    else if (o.is("--friction"))
      friction = o.number();
    else
      o.unknown();
  }
  if (std::isnan(y_min)) y_min = -y_max;
  if (load > 0.0 && !(speed > 0.0)) o.fail("--load needs --speed > 0 (the creepages are relative to it)");
  try {
    const rc::WheelProfile wheel = wheel_file.empty() ? rc::makeS1002() : rc::loadWheelProfile(wheel_file);
    const rc::ProfileCurve rail =
        rail_file.empty() ? rc::makeUic60Rail(incl) : rc::loadRailProfile(rail_file, {}, {}, incl);
    rc::WheelsetTrackSpec spec;
    spec.track_gauge = gauge;
    spec.back_to_back = b2b;
    spec.taping_line_from_flange_back = taping;
    spec.nominal_radius = radius;
    rc::WheelContactOptions options;
    options.friction = friction;
    rc::ContactGeometryTable table(wheel, rail, spec, options);
    rc::LoadCase lc;
    lc.wheel_load = load;
    lc.speed = speed;
    lc.free_rolling = !fixed_spin;
    const std::vector<rc::ContactGeometryRow> rows = table.table(y_min, y_max, dy, yaw, lc, yaw_per_y);
    int failed = 0, unloaded = 0;
    for (const rc::ContactGeometryRow& r : rows) {
      if (r.ok && (load <= 0.0 || r.loaded_ok)) continue;
      if (r.ok) {
        ++unloaded;
        std::fprintf(stderr, "contact_geometry: row y = %.6g m, yaw = %.6g rad: loaded columns left empty: %s\n", r.y,
                     r.yaw, r.failure.c_str());
        continue;
      }
      ++failed;
      std::fprintf(stderr, "contact_geometry: row y = %.6g m, yaw = %.6g rad not solved: %s\n", r.y, r.yaw,
                   r.failure.c_str());
    }
    if (failed == static_cast<int>(rows.size())) {
      std::fprintf(stderr, "contact_geometry: no row of %zu solved (wheel %s, rail %s); %s not written\n", rows.size(),
                   wheel_file.empty() ? "S1002" : wheel_file.c_str(), rail_file.empty() ? "UIC60" : rail_file.c_str(),
                   out.c_str());
      return 1;
    }
    const int written = rc::writeContactGeometryCsv(out, rows);
    std::string note;
    if (failed > 0) note += "; " + std::to_string(failed) + " of " + std::to_string(rows.size()) + " rows not solved";
    if (unloaded > 0) note += "; " + std::to_string(unloaded) + " with the loaded columns empty";
    std::printf("wrote %s (%d rows%s%s)\n", out.c_str(), written, note.c_str(), note.empty() ? "" : ", listed above");
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
      f.close();
      if (!f) throw std::runtime_error(conicity_out + ": write failed");
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
