// The one YAML reader of the input files: every refusal has the form "<file>: <path>: <what> (line N)",
// with ", got <value>" when there is a value, and is thrown as the loader's own error type.
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "rail_core/yaml_reader.hpp"

namespace {

using rail::core::MapReader;

struct LoaderError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
[[noreturn]] void raiseLoaderError(const std::string& message) { throw LoaderError(message); }

const char* const kText =
    "name: demo\n"                                                              // 1
    "beam:\n"                                                                   // 2
    "  E: 2.1e11\n"                                                             // 3
    "  rho: heavy\n"                                                            // 4
    "  k: .inf\n"                                                               // 5
    "  n: 6.5\n"                                                                // 6
    "  p: [1, 2]\n"                                                             // 7
    "  far: 2e12\n"                                                             // 8
    "  negative: -3\n"                                                          // 9
    "list: [0.5, x, 2]\n"                                                       // 10
    "vec: [1, 2, 3]\n"                                                          // 11
    "long: [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18]\n";  // 12

// The message of the loader error thrown by read, or "no error".
template <typename F>
std::string refusal(F&& read) {
  try {
    const YAML::Node doc = rail::core::parseYaml(kText, "in.yaml", raiseLoaderError);
    MapReader root(doc, "", "in.yaml", raiseLoaderError);
    read(root);
  } catch (const LoaderError& e) {
    return e.what();
  }
  return "no error";
}

TEST(YamlReader, EachRefusalNamesFileFieldValueAndLine) {
  EXPECT_EQ(refusal([](MapReader& r) { r.map("beam").number("G"); }), "in.yaml: beam.G: required key missing (line 3)");
  EXPECT_EQ(refusal([](MapReader& r) { r.map("beam").number("rho"); }),
            "in.yaml: beam.rho: must be a number, got 'heavy' (line 4)");
  EXPECT_EQ(refusal([](MapReader& r) { r.map("beam").number("k"); }),
            "in.yaml: beam.k: must be a finite number, got .inf (line 5)");
  EXPECT_EQ(refusal([](MapReader& r) { r.map("beam").positiveInteger("n", 10); }),
            "in.yaml: beam.n: must be a whole number, got '6.5' (line 6)");
  EXPECT_EQ(refusal([](MapReader& r) { r.map("beam").number("p"); }),
            "in.yaml: beam.p: must be a number, got [1, 2] (line 7)");
  EXPECT_EQ(refusal([](MapReader& r) { r.map("beam").positive("far", 1e12, "N/m"); }),
            "in.yaml: beam.far: must be at most 1e+12 N/m, got 2e+12 (line 8)");
  EXPECT_EQ(refusal([](MapReader& r) { r.map("beam").nonNegative("negative", 10.0, "m"); }),
            "in.yaml: beam.negative: must not be negative, got -3 (line 9)");
  EXPECT_EQ(refusal([](MapReader& r) { r.map("beam").bounded("far", 1e9, "N"); }),
            "in.yaml: beam.far: magnitude must be at most 1e+09 N, got 2e+12 (line 8)");
  EXPECT_EQ(refusal([](MapReader& r) {
              std::vector<double> v;
              r.numberList("list", v);
            }),
            "in.yaml: list[1]: must be a number, got 'x' (line 10)");
  EXPECT_EQ(refusal([](MapReader& r) { r.vector3("list", 10.0, "m"); }),
            "in.yaml: list[1]: must be a number, got 'x' (line 10)");
  EXPECT_EQ(refusal([](MapReader& r) { r.vector3("long", 10.0, "m"); }),
            "in.yaml: long: must be a list of 3 numbers, got a list (line 12)");
  EXPECT_EQ(refusal([](MapReader& r) { r.map("name"); }),
            "in.yaml: name: must be a map of keys to values, got 'demo' (line 1)");
}

TEST(YamlReader, UnknownKeysAreRefusedListingTheKnownOnes) {
  EXPECT_EQ(refusal([](MapReader& r) {
              std::string name;
              r.string("name", name);
              r.child("beam");
              r.child("list");
              r.finish();
            }),
            "in.yaml: vec: unknown key (known here: beam, list, name) (line 11)");
}

TEST(YamlReader, OptionalKeysKeepTheirDefaultAndValuesAreReadExactly) {
  EXPECT_EQ(refusal([](MapReader& r) {
              double absent = 7.5;
              r.number("absent", absent);
              EXPECT_EQ(absent, 7.5);
              MapReader beam = r.map("beam");
              EXPECT_EQ(beam.number("E"), 2.1e11);
              EXPECT_EQ(beam.optionalBounded("G", -1.0, 1e12, "Pa"), -1.0);
              EXPECT_EQ(r.vector3("vec", 10.0, "m"), Eigen::Vector3d(1.0, 2.0, 3.0));
              EXPECT_EQ(r.optionalVector3("nothing", 10.0, "m"), Eigen::Vector3d::Zero());
            }),
            "no error");
}

TEST(YamlReader, ParsingRefusesSyntaxErrorsDuplicatesAndEmptyFiles) {
  auto parseError = [](const std::string& text) -> std::string {
    try {
      rail::core::parseYaml(text, "in.yaml", raiseLoaderError);
    } catch (const LoaderError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_EQ(parseError("a: [1, 2\n"), "in.yaml: not valid YAML: end of sequence flow not found (line 2)");
  EXPECT_EQ(parseError("a:\n  b: 1\n  b: 2\n"), "in.yaml: a.b: given twice (lines 2 and 3): remove one");
  EXPECT_EQ(parseError("# only a comment\n"), "in.yaml: is empty");
}

TEST(YamlReader, WithoutARaiseHookTheErrorIsARuntimeError) {
  const YAML::Node doc = rail::core::parseYaml("a: 1\n", "in.yaml");
  MapReader r(doc, "", "in.yaml");
  try {
    r.number("b");
    FAIL() << "no error";
  } catch (const LoaderError&) {
    FAIL() << "a loader's type without its hook";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "in.yaml: b: required key missing (line 1)");
  }
  EXPECT_THROW(rail::core::loadYamlFile("/nonexistent/in.yaml", raiseLoaderError), LoaderError);
}

}  // namespace
