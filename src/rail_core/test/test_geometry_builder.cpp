// Scene -> track geometry: the rails' gauge points are the scene's gauge apart on a canted curve, scene
// fields reach the GeometrySpec, irregularities that are off cost nothing, errors name the scene field.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <string>

#include "rail_core/geometry_builder.hpp"
#include "rail_core/scene_loader.hpp"

using namespace rail::core;
namespace rc = rail::contact;

namespace {

const std::string kData = RAILSIM_TEST_DATA_DIR;

// Straight, clothoid with a cant ramp, canted circular curve to the right, straight.
const std::string kCurve = R"(name: canted_curve
track:
  gauge: 1.668
  gauge_measuring_depth: 0.014
  cant_reference_width: 1.733
  rail_inclination: 1/20
  data: track_data.yaml
  segments:
    - {type: straight, length: 20.0}
    - {type: transition, length: 40.0, direction: right, radius_start: 0, radius_end: 300.0, cant_start: 0.0, cant_end: 0.15}
    - {type: circular, length: 60.0, direction: right, radius: 300.0, cant: 0.15}
    - {type: transition, length: 40.0, direction: right, radius_start: 300.0, radius_end: 0, cant_start: 0.15, cant_end: 0.0}
    - {type: straight, length: 20.0}
IRREGULARITIES
moving_loads:
  start_arc_length: 10.0
  speed: 10.0
  loads:
    - {offset: 0.0, rail: both, vertical: 100000.0}
EFFECTS
)";

Scene curveScene(const std::string& irregularities, const std::string& effects) {
  std::string text = kCurve;
  text.replace(text.find("IRREGULARITIES"), 14, irregularities);
  text.replace(text.find("EFFECTS"), 7, effects);
  return loadSceneText(text, "canted_curve.yaml", kData);
}

// Gauge point of one rail found in the world, independently of the builder's tilted-profile route: every
// node of the (untilted) profile is placed on the rail with the geometry's rail frame, expressed in the
// centre line's track frame (n lateral, b normal), the highest point in b is the running surface, and the
// gauge point is where the gauge side first lies `depth` below it (linear between the 0.1 mm nodes).
Eigen::Vector2d worldGaugePointNB(const rc::TrackGeometry& g, const rc::ProfileCurve& profile, rc::RailSide side,
                                  double s, double depth) {
  rc::TrackPoint c;
  g.centre(s, c);
  rc::RailPoint rp;
  g.rail(side, s, rp);
  const rc::ProfilePoints pts = profile.nodes();
  std::vector<Eigen::Vector2d> nb(pts.size());
  int top = 0;
  for (std::size_t k = 0; k < pts.size(); ++k) {
    const Eigen::Vector3d r = rc::TrackGeometry::railSurface(rp, pts[k].x(), pts[k].y(), 0.0, 0.0).r;
    const Eigen::Vector3d d = c.R_track_to_world.transpose() * (r - c.p_center_in_world);
    nb[k] = Eigen::Vector2d(d.y(), d.z());
    if (nb[k].y() > nb[top].y()) top = static_cast<int>(k);
  }
  // Profile nodes run field -> gauge (y toward the centre increasing); the gauge side is after the top.
  const double level = nb[top].y() - depth;
  for (std::size_t k = top; k + 1 < nb.size(); ++k) {
    if (nb[k].y() >= level && nb[k + 1].y() < level) {
      const double w = (nb[k].y() - level) / (nb[k].y() - nb[k + 1].y());
      return (1.0 - w) * nb[k] + w * nb[k + 1];
    }
  }
  ADD_FAILURE() << "no gauge point found";
  return Eigen::Vector2d::Zero();
}

}  // namespace

// On the canted curve and its cant ramps the gauge points of the two rails, measured in the canted track
// plane, are the scene's gauge apart. Tolerance 2e-6 m: the geometry table is cubic Hermite at 0.1 m
// (~1e-8 m on these curves) and the gauge point is interpolated linearly between 0.1 mm profile nodes on
// the R13 corner arc (chord sag (1e-4)^2 / (8 * 0.013) = 1e-7 m).
TEST(GeometryBuilder, GaugePointsAreTheGaugeApartOnCantedCurve) {
  const Scene scene = curveScene("", "effects: {track_model: flexible}");
  const rc::TrackGeometry g = buildTrackGeometry(scene);
  const rc::ProfileCurve profile = railProfileCurve(scene);
  for (double s : {5.0, 30.0, 55.0, 90.0, 125.0, 170.0}) {
    const Eigen::Vector2d left = worldGaugePointNB(g, profile, rc::RailSide::kLeft, s, 0.014);
    const Eigen::Vector2d right = worldGaugePointNB(g, profile, rc::RailSide::kRight, s, 0.014);
    EXPECT_NEAR(left.x() - right.x(), 1.668, 2e-6) << "s = " << s;
  }
  // The circular curve really is canted: the outer rail stands higher than the inner one by
  // cant * 2h / e (doc/geometry.md); 1e-9 m (straight-line geometry, round-off and table error only).
  const rc::GeometrySpec& spec = g.spec();
  rc::RailPoint l, r;
  g.rail(rc::RailSide::kLeft, 90.0, l);
  g.rail(rc::RailSide::kRight, 90.0, r);
  // Right-hand curve: the outer rail is the left one; signed cant < 0 raises it.
  const double dz = l.p_origin_in_world.z() - r.p_origin_in_world.z();
  EXPECT_NEAR(dz, 0.15 * 2.0 * spec.rail_half_spacing / 1.733, 1e-9);
}

// The scene's fields reach the GeometrySpec: signed curvature (right curve < 0), signed cant (right
// curve raises the left rail: < 0), atan of the inclination ratio, cant base, s_start. Exact (1e-15)
// except the curvature, 1 ulp-level.
TEST(GeometryBuilder, SpecCarriesSignedCurvatureCantAndInclination) {
  const Scene scene = curveScene("", "effects: {track_model: flexible}");
  const rc::GeometrySpec spec = geometrySpec(scene);
  ASSERT_EQ(spec.segments.size(), 5u);
  EXPECT_EQ(spec.segments[1].type, rc::SegmentSpec::Type::Transition);
  EXPECT_DOUBLE_EQ(spec.segments[1].curvature_start, 0.0);
  EXPECT_DOUBLE_EQ(spec.segments[1].curvature_end, -1.0 / 300.0);
  EXPECT_DOUBLE_EQ(spec.segments[2].curvature_start, -1.0 / 300.0);
  EXPECT_DOUBLE_EQ(spec.segments[2].cant_start, -0.15);
  EXPECT_DOUBLE_EQ(spec.segments[3].cant_end, 0.0);
  EXPECT_DOUBLE_EQ(spec.rail_inclination, std::atan(0.05));
  EXPECT_DOUBLE_EQ(spec.cant_reference_width, 1.733);
  EXPECT_DOUBLE_EQ(spec.s_start, 0.0);
  // The rail profile origin lies outside half the gauge by the gauge point's offset: for the 60E1 head
  // (72 mm wide) the gauge face 14 mm down is 30-40 mm from the rail axis.
  EXPECT_GT(spec.rail_half_spacing - 0.834, 0.030);
  EXPECT_LT(spec.rail_half_spacing - 0.834, 0.040);
}

// Irregularities described in the scene but switched off (effects.irregularities: false) build nothing:
// the geometry is bit-identical to the one of the scene without irregularity data (same table step, no
// irregularities, same rail points). Switched on, the same data changes the rails (the test can fail).
TEST(GeometryBuilder, IrregularitiesOffCostNothing) {
  const std::string psd =
      "  irregularities: {source: psd, psd: fra_class_4, seed: 7, wavelength_min: 2.0, wavelength_max: 60.0}";
  const Scene plain = curveScene("", "effects: {track_model: flexible}");
  const Scene off = curveScene(psd, "effects: {track_model: flexible, irregularities: false}");
  const Scene on = curveScene(psd, "effects: {track_model: flexible, irregularities: true}");
  EXPECT_TRUE(buildIrregularities(off).empty());
  const rc::TrackGeometry g_plain = buildTrackGeometry(plain);
  const rc::TrackGeometry g_off = buildTrackGeometry(off);
  const rc::TrackGeometry g_on = buildTrackGeometry(on);
  EXPECT_FALSE(g_off.hasIrregularities());
  EXPECT_TRUE(g_on.hasIrregularities());
  EXPECT_EQ(g_off.tableStep(), g_plain.tableStep());
  EXPECT_EQ(g_off.numIntervals(), g_plain.numIntervals());
  double max_on_difference = 0.0;
  for (double s = 0.0; s <= 180.0; s += 0.37) {
    for (rc::RailSide side : {rc::RailSide::kLeft, rc::RailSide::kRight}) {
      rc::RailPoint a, b, c;
      g_plain.rail(side, s, a);
      g_off.rail(side, s, b);
      g_on.rail(side, s, c);
      EXPECT_EQ(a.p_origin_in_world, b.p_origin_in_world);
      EXPECT_EQ(a.R_rail_to_world, b.R_rail_to_world);
      max_on_difference = std::max(max_on_difference, (c.p_origin_in_world - a.p_origin_in_world).norm());
    }
  }
  EXPECT_GT(max_on_difference, 1e-4);  // FRA class 4 over 2-60 m: millimetres
}

// A PSD realisation is drawn with enough harmonics not to repeat within the track.
TEST(GeometryBuilder, PsdRealisationDoesNotRepeatWithinTrack) {
  const Scene on =
      curveScene("  irregularities: {source: psd, psd: german_low, wavelength_min: 0.5, wavelength_max: 120.0}",
                 "effects: {track_model: flexible, irregularities: true}");
  const rc::Irregularities irr = buildIrregularities(on);
  EXPECT_GT(irr.repeatLength(), on.track.length());
  EXPECT_NEAR(irr.shortestWavelength(), 0.5, 1e-12);
  const rc::TrackGeometry g = buildTrackGeometry(on);
  EXPECT_LE(g.tableStep(), 0.5 / 8.0 + 1e-12);
}

// Errors from the irregularity and geometry code come back as SceneError naming the scene file and field.
TEST(GeometryBuilder, ErrorsNameSceneFileAndField) {
  // A table whose s steps back on its line 5.
  const std::string csv = ::testing::TempDir() + "bad_irregularities.csv";
  {
    std::ofstream out(csv);
    out << "# s, alignment, vertical level, cross level, gauge (m)\ns, alignment, vertical_level, cross_level, gauge\n"
           "0.0, 0.0, 0.0, 0.0, 0.0\n2.0, 0.001, 0.0, 0.0, 0.0\n1.0, 0.001, 0.0, 0.0, 0.0\n";
  }
  const Scene bad_file = curveScene("  irregularities: {source: file, file: " + csv + "}",
                                    "effects: {track_model: flexible, irregularities: true}");
  try {
    buildTrackGeometry(bad_file);
    FAIL() << "no error";
  } catch (const SceneError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find("canted_curve.yaml: track.irregularities.file: "), 0u) << m;
    EXPECT_NE(m.find("bad_irregularities.csv:5"), std::string::npos) << m;
  }
  // A curve tighter than half the rail spacing is refused by the geometry (the scene loader accepts any
  // radius > 0).
  Scene tight = curveScene("", "effects: {track_model: flexible}");
  tight.track.segments[2].radius = 0.5;
  tight.track.segments[1].radius_end = 0.5;
  tight.track.segments[3].radius_start = 0.5;
  try {
    buildTrackGeometry(tight);
    FAIL() << "no error";
  } catch (const SceneError& e) {
    const std::string m = e.what();
    EXPECT_EQ(m.find("canted_curve.yaml: track.segments[1].curvature"), 0u) << m;
  }
}
