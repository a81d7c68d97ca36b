// Command-line helpers shared by the project's tools and benchmark programs: -h / --help prints the
// usage and exits 0; a positional argument that is not a number is refused (exit 2) instead of being
// read as 0 by atoi.
#pragma once

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <sstream>
#include <string>
#include <vector>

#include "rail_contact/format.hpp"

namespace rail {
namespace tools {

/// True, after printing usage to stdout, when any argument is -h or --help.
inline bool helpRequested(int argc, char** argv, const char* usage) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "-h" || a == "--help") {
      std::fputs(usage, stdout);
      return true;
    }
  }
  return false;
}

/// Refuses any argument that looks like an option ("-x", "--x"; not a negative number): exit 2 naming it.
/// For the programs that take positional arguments only.
inline void refuseOptions(int argc, char** argv, const char* usage) {
  for (int i = 1; i < argc; ++i) {
    const char* a = argv[i];
    if (a[0] == '-' && a[1] != '\0' && !(a[1] >= '0' && a[1] <= '9') && a[1] != '.') {
      std::fprintf(stderr, "%s: unknown option %s\n%s", argv[0], a, usage);
      std::exit(2);
    }
  }
}

/// Positional argument i (1-based) as a number, fallback when absent; a value that is not a finite
/// number, or below min_value, exits 2 with the program's name, the argument and the usage.
inline double positionalNumber(int argc, char** argv, int i, double fallback, double min_value, const char* usage) {
  if (i >= argc) return fallback;
  const char* text = argv[i];
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(v) || v < min_value) {
    std::fprintf(stderr, "%s: argument %d: '%s' is not a number >= %s\n%s", argv[0], i, text,
                 contact::formatNumber(min_value).c_str(), usage);
    std::exit(2);
  }
  return v;
}

/// Positional argument i (1-based) as the index of its value in choices (nullptr-terminated), fallback when
/// absent; any other value exits 2 with the program's name, the argument, the choices and the usage.
inline int positionalChoice(int argc, char** argv, int i, const char* const* choices, int fallback, const char* usage) {
  if (i >= argc) return fallback;
  std::string allowed;
  for (int k = 0; choices[k] != nullptr; ++k) {
    if (argv[i] == std::string(choices[k])) return k;
    allowed += (k == 0 ? "" : "|") + std::string(choices[k]);
  }
  std::fprintf(stderr, "%s: argument %d: '%s' is not one of %s\n%s", argv[0], i, argv[i], allowed.c_str(), usage);
  std::exit(2);
}

/// Refuses more than max_positional arguments (exit 2).
inline void atMostArguments(int argc, char** argv, int max_positional, const char* usage) {
  if (argc - 1 > max_positional) {
    std::fprintf(stderr, "%s: unexpected argument '%s'\n%s", argv[0], argv[max_positional + 1], usage);
    std::exit(2);
  }
}

/// startTool's max_positional for a tool that parses its own options (only -h / --help is handled) and for
/// one that takes any number of positional arguments.
constexpr int kOwnOptions = -1;
constexpr int kAnyCount = INT_MAX;

/// A tool's argument prologue in one call, `if (startTool(argc, argv, usage, n)) return 0;`: true after
/// printing the usage for -h / --help; else, unless n is kOwnOptions, an option or more than n arguments
/// exits 2.
inline bool startTool(int argc, char** argv, const char* usage, int max_positional) {
  if (helpRequested(argc, argv, usage)) return true;
  if (max_positional == kOwnOptions) return false;
  refuseOptions(argc, argv, usage);
  atMostArguments(argc, argv, max_positional, usage);
  return false;
}

/// A tool's named options, read in order:
///   for (Options o(argc, argv, "name"); o.next();)
///     if (o.is("--csv")) csv = o.value(); else if (o.is("--gauge")) gauge = o.number(); else o.unknown();
/// A missing or malformed value, or an unknown option, is one line on stderr naming the option, then exit 2.
class Options {
 public:
  Options(int argc, char** argv, const char* tool) : argc_(argc), argv_(argv), tool_(tool) {}
  bool next() {
    if (++i_ >= argc_) return false;
    option_ = argv_[i_];
    return true;
  }
  bool is(const char* option) const { return option_ == option; }
  const std::string& option() const { return option_; }
  // The option's value, the next argument.
  std::string value() {
    if (i_ + 1 >= argc_) fail(option_ + " needs a value");
    return argv_[++i_];
  }
  // The value as a finite number, and as one above zero.
  double number() { return parse(value(), false); }
  double positive() { return parse(value(), true); }
  // The value as comma-separated positive numbers.
  std::vector<double> positives() {
    std::vector<double> out;
    std::stringstream ss(value());
    for (std::string item; std::getline(ss, item, ',');) out.push_back(parse(item, true));
    return out;
  }
  [[noreturn]] void unknown() const { fail("unknown option " + option_); }
  [[noreturn]] void fail(const std::string& what) const {
    std::fprintf(stderr, "%s: %s (%s --help lists the options)\n", tool_, what.c_str(), tool_);
    std::exit(2);
  }

 private:
  double parse(const std::string& text, bool positive) const {
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0' || !std::isfinite(v) || (positive && v <= 0.0))
      fail(option_ + ": not a " + (positive ? "positive " : "") + "number (" + text + ")");
    return v;
  }

  int argc_;
  char** argv_;
  const char* tool_;
  int i_ = 0;
  std::string option_;
};

/// Benchmark programs' clock: seconds from t0 to t1 (now when omitted), and the median of timings.
using BenchClock = std::chrono::steady_clock;
inline double secondsSince(BenchClock::time_point t0, BenchClock::time_point t1 = BenchClock::now()) {
  return std::chrono::duration<double>(t1 - t0).count();
}
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

/// A tool's main in one call, `return runReportingErrors("name", run, argc, argv);`: an exception thrown by
/// run (a file that cannot be read, a field out of range) is one line "name: what" on stderr and exit 1.
inline int runReportingErrors(const char* name, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", name, e.what());
    return 1;
  }
}

}  // namespace tools
}  // namespace rail
