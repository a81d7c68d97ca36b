// Track data file: the shipped paper_track.yaml loads with the paper's Table 1 / Table 2 values, and bad
// input throws with "<file>: <key.path>: <what>, got <value> (line N)", the form of every input file.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "rail_track_node/track_data.hpp"

namespace rt = rail::track;

namespace {

std::string paperTrackPath() {
#ifdef RAIL_TRACK_CONFIG_DIR
  return std::string(RAIL_TRACK_CONFIG_DIR) + "/paper_track.yaml";
#else
  // test/ -> rail_track_node/ -> src/ -> workspace root
  const std::string here = __FILE__;
  return here.substr(0, here.rfind("/src/rail_track_node/")) + "/config/track/paper_track.yaml";
#endif
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Replaces the first occurrence of `from` (must exist) in text.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

std::string errorOf(const std::string& text) {
  try {
    rt::parseTrackData(text, "track.yaml");
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "no exception";
}

}  // namespace

// Values must be the paper's tables exactly (as decimal literals): compared with == after parsing.
TEST(TrackData, PaperFileHasTableValues) {
  const rt::TrackData d = rt::loadTrackData(paperTrackPath());
  EXPECT_EQ(d.rail.E, 2.10e11);
  EXPECT_EQ(d.rail.G, 8.08e10);
  EXPECT_EQ(d.rail.A, 7.67e-3);
  EXPECT_EQ(d.rail.J, 3.55e-5);
  EXPECT_EQ(d.rail.I_y, 3.04e-5);
  EXPECT_EQ(d.rail.I_z, 5.12e-6);
  EXPECT_EQ(d.rail.rho, 7860.0);
  EXPECT_EQ(d.sleeper.E, 3.10e10);
  EXPECT_EQ(d.sleeper.A, 5.6e-2);
  EXPECT_EQ(d.sleeper.rho, 2750.0);
  // Rayleigh coefficients: the physical (swapped) reading of Table 1, see doc/fe.md.
  EXPECT_EQ(d.rail.rayleigh_alpha, 0.94);
  EXPECT_EQ(d.rail.rayleigh_beta, 3.98e-4);
  EXPECT_EQ(d.pad.k(2), 1.30e8);
  EXPECT_EQ(d.pad.k_roll, 2.00e5);
  EXPECT_EQ(d.pad.c(2), 1.50e5);
  EXPECT_EQ(d.ballast.k(2), 6.19e7);
  EXPECT_EQ(d.ballast.mass, 226.41);
  EXPECT_EQ(d.sleeper_interaction.k(0), 3.92e7);
  EXPECT_EQ(d.layout.rail_elements_between_sleepers, 6);
  EXPECT_EQ(d.layout.ballast_nodes.size(), 4u);
  EXPECT_TRUE(d.absorbing_ends.enabled);
}

TEST(TrackData, UnknownKeyThrows) {
  const std::string text = readFile(paperTrackPath());
  EXPECT_EQ(errorOf(text + "\nextra_section: 1\n"),
            "track.yaml: extra_section: unknown key (known here: absorbing_ends, ballast, layout, pad, rail, sleeper, "
            "sleeper_interaction) (line 94)");
  EXPECT_EQ(errorOf(replaced(text, "  mass: 226.41", "  mass: 226.41\n  colour: 3")),
            "track.yaml: ballast.colour: unknown key (known here: c_longitudinal, c_transversal, c_vertical, "
            "k_longitudinal, k_transversal, k_vertical, mass) (line 58)");
}

// yaml-cpp would keep the first of two equal keys: the second must not be silently dropped.
TEST(TrackData, KeyGivenTwiceThrowsNamingBothLines) {
  const std::string text = readFile(paperTrackPath());
  // Line 9 is the rail's E; the copy goes right below it.
  EXPECT_EQ(errorOf(replaced(text, "  E: 2.10e11", "  E: 2.10e11\n  E: 2.10e12")),
            "track.yaml: rail.E: given twice (lines 9 and 10): remove one");
}

TEST(TrackData, MissingKeyThrows) {
  const std::string text = readFile(paperTrackPath());
  EXPECT_EQ(errorOf(replaced(text, "  sleeper_spacing: 0.60", "")),
            "track.yaml: layout.sleeper_spacing: required key missing (line 72)");
  // A misspelt key is reported as the missing required key first.
  EXPECT_EQ(errorOf(replaced(text, "  k_roll:", "  k_rol:")), "track.yaml: pad.k_roll: required key missing (line 40)");
}

TEST(TrackData, WrongTypeThrows) {
  const std::string text = readFile(paperTrackPath());
  EXPECT_EQ(errorOf(replaced(text, "  rho: 7860.0", "  rho: heavy")),
            "track.yaml: rail.rho: must be a number, got 'heavy' (line 16)");
  EXPECT_EQ(errorOf(replaced(text, "rail_elements_between_sleepers: 6", "rail_elements_between_sleepers: 6.5")),
            "track.yaml: layout.rail_elements_between_sleepers: must be a whole number, got '6.5' (line 78)");
  EXPECT_EQ(errorOf(replaced(text, "  enabled: true", "  enabled: [1]")),
            "track.yaml: absorbing_ends.enabled: must be a single value, got [1] (line 91)");
}

TEST(TrackData, NonPositiveThrows) {
  const std::string text = readFile(paperTrackPath());
  EXPECT_EQ(errorOf(replaced(text, "  k_vertical: 6.19e7", "  k_vertical: -6.19e7")),
            "track.yaml: ballast.k_vertical: must be positive, got -6.19e+07 (line 51)");
  EXPECT_EQ(errorOf(replaced(text, "  E: 3.10e10", "  E: 0")),
            "track.yaml: sleeper.E: must be positive, got 0 (line 27)");
  EXPECT_EQ(errorOf(replaced(text, "ballast_nodes: [0, 1, 4, 5]", "ballast_nodes: [0, 7]")),
            "track.yaml: layout.ballast_nodes: entries must be distinct sleeper node indices 0..5, got 7 (line 86)");
}

// Values above a physical bound (and inf) are refused naming the key and the bound, never clamped.
TEST(TrackData, AbsurdOrInfiniteThrows) {
  const std::string text = readFile(paperTrackPath());
  EXPECT_EQ(errorOf(replaced(text, "  rho: 7860.0", "  rho: .inf")),
            "track.yaml: rail.rho: must be a finite number, got .inf (line 16)");
  EXPECT_EQ(errorOf(replaced(text, "sleeper_length: 2.60", "sleeper_length: 1e300")),
            "track.yaml: layout.sleeper_length: must be at most 10 m, got 1e+300 (line 79)");
  EXPECT_EQ(errorOf(replaced(text, "  k_vertical: 1.30e8", "  k_vertical: 2e12")),
            "track.yaml: pad.k_vertical: must be at most 1e+12 N/m, got 2e+12 (line 40)");
  EXPECT_EQ(errorOf(replaced(text, "rayleigh_alpha: 0.94", "rayleigh_alpha: .inf")),
            "track.yaml: rail.rayleigh_alpha: must be a finite number, got .inf (line 21)");
  EXPECT_EQ(errorOf(replaced(text, "design_frequency: 500.0", "design_frequency: .inf")),
            "track.yaml: absorbing_ends.design_frequency: must be a finite number, got .inf (line 92)");
  // A sleeper too short for the rail seats: the message names both keys.
  EXPECT_EQ(errorOf(replaced(text, "sleeper_length: 2.60", "sleeper_length: 1e-300")),
            "track.yaml: layout.rail_lateral_offset: must be smaller than half of layout.sleeper_length "
            "(1e-300 / 2), got 0.87 (line 72)");
  // At the bound: accepted.
  EXPECT_EQ(errorOf(replaced(text, "  k_vertical: 1.30e8", "  k_vertical: 1e12")), "no exception");
}

TEST(TrackData, MissingFileThrows) { EXPECT_THROW(rt::loadTrackData("/nonexistent/track.yaml"), std::runtime_error); }
