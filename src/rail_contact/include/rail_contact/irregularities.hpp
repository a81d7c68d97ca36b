// Track irregularities: deviations of the two rails from the design geometry, functions of the track
// arc length s. Built once (from a CSV table or as a seeded realisation of a published PSD), constant
// afterwards; TrackGeometry samples them when it builds its tables, so they add nothing to the cost of a
// time step. See doc/geometry.md for the sign conventions (EN 13848-1 quantities).
#pragma once

#include <array>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace rail {
namespace contact {

/// The four irregularity channels (m), in the track frame at s:
///  - alignment:      lateral position of the track centre (mean of the two rails), +n (left) positive;
///  - vertical_level: vertical position of the track centre (mean of the two rails), +b (up) positive;
///  - cross_level:    height of the right rail minus height of the left rail (same sign as cant);
///  - gauge:          track gauge minus nominal gauge, wider positive.
/// Left rail: lateral a + g/2 (outward), vertical v - c/2. Right rail: lateral a - g/2, vertical v + c/2.
struct IrregularitySample {
  double alignment = 0.0;
  double vertical_level = 0.0;
  double cross_level = 0.0;
  double gauge = 0.0;
};

/// Value and first and second derivatives with respect to s (m, 1, 1/m) of every channel.
struct IrregularityState {
  IrregularitySample value;
  IrregularitySample d_ds;
  IrregularitySample d2_ds2;
};

enum class IrregularityChannel { kAlignment = 0, kVerticalLevel = 1, kCrossLevel = 2, kGauge = 3 };

/// Published track-irregularity spectra (see psdValue for formulas and sources).
enum class PsdSpectrum {
  kFraClass1,
  kFraClass2,
  kFraClass3,
  kFraClass4,
  kFraClass5,
  kFraClass6,  // US FRA track classes
  kGermanLow,
  kGermanHigh,  // German / ERRI low- and high-disturbance spectra
};

/// "fra_class_1" .. "fra_class_6", "german_low", "german_high" -> spectrum; throws std::runtime_error
/// naming the unknown value and the accepted ones.
PsdSpectrum psdSpectrumFromName(const std::string& name);

/// One-sided PSD S(Omega) in m^2/(rad/m) at the spatial angular frequency Omega (rad/m, > 0) of one
/// channel, so that the variance in a band is the integral of S over Omega. The cross level is returned
/// as the PSD of the rails' height difference (m), also for the German spectra whose published form is
/// that of the cross-level angle (converted with the spectra's own base 2b = 1.5 m).
double psdValue(PsdSpectrum spectrum, IrregularityChannel channel, double Omega);

/// Seeded realisation of a PSD over a band of wavelengths.
struct PsdRealisationSpec {
  PsdSpectrum spectrum = PsdSpectrum::kFraClass6;
  double wavelength_min = 1.0;    // m, shortest wavelength generated (> 0)
  double wavelength_max = 120.0;  // m, longest wavelength generated (> wavelength_min)
  std::uint64_t seed = 1;         // std::mt19937_64 seed of the random phases
  int harmonics = 4096;           // harmonics per channel (uniform in Omega over the band)
  double s_reference = 0.0;       // m, arc length at which the phases are the drawn ones
  // Channels generated; a channel that is off is identically zero (its phases are still drawn, so the
  // other channels do not change when one is switched off).
  bool alignment = true;
  bool vertical_level = true;
  bool cross_level = true;
  bool gauge = true;
};

/// Irregularities as a function of the track arc length s. The default-constructed object is "no
/// irregularities" (empty() is true). Evaluation is allocation-free but meant for build time.
class Irregularities {
 public:
  Irregularities() = default;

  /// Reads a CSV table: one row per station, 5 columns "s, alignment, vertical level, cross level,
  /// gauge", all in metres; '#' starts a comment; blank lines are skipped; one optional header line of
  /// names before the first row. s must increase strictly; at least two rows. Values are interpolated
  /// by C1 cubic Hermite (slopes from three-point differences) and held constant beyond the table.
  /// Errors throw std::runtime_error "<file>:<line>: <what>".
  static Irregularities fromCsvFile(const std::string& path);
  /// Same as fromCsvFile, reading from a stream; `name` is used in error messages.
  static Irregularities fromCsvStream(std::istream& in, const std::string& name);

  /// Sum of harmonics with deterministic amplitudes sqrt(2 S(Omega_k) dOmega) and random phases:
  ///   x(s) = sum_k a_k cos(Omega_k (s - s_reference) + phi_k),  Omega_k = Omega_min + (k + 1/2) dOmega,
  /// Omega in [2 pi / wavelength_max, 2 pi / wavelength_min]. Phases are drawn from std::mt19937_64
  /// (whose output sequence is fixed by the C++ standard) converted to [0, 2 pi) by integer arithmetic,
  /// not by a std:: distribution, so a seed gives the same realisation on every standard library (up to
  /// the last-bit differences of std::cos). The harmonics' difference frequencies are multiples of
  /// dOmega, so the signal's statistics repeat after repeatLength() metres: choose `harmonics` so that
  /// this exceeds the track length.
  static Irregularities fromPsd(const PsdRealisationSpec& spec);

  bool empty() const { return kind_ == Kind::kNone; }

  /// Value and derivatives at s (m).
  void evaluate(double s, IrregularityState& out) const;

  /// Stations evaluated (evaluate() and sampleUniform()) by all objects of the process since it started:
  /// a cost figure. TrackGeometry tabulates the irregularities when it is built, so a run adds none.
  static long long stationsEvaluated();

  /// Values and derivatives at s0 + i h, i = 0 .. out.size() - 1 (the caller sizes out). Same result as
  /// evaluate() to round-off; a PSD realisation is summed by a rotation recurrence (re-anchored every
  /// 256 stations), which makes building long tables cheap.
  void sampleUniform(double s0, double h, std::vector<IrregularityState>& out) const;

  /// Shortest wavelength present (m): the PSD band's lower end, or twice the smallest row spacing of a
  /// table; +infinity when empty. TrackGeometry checks its table step against it.
  double shortestWavelength() const;

  /// PSD realisation: 2 pi / dOmega (m), the period of the harmonics' difference frequencies (beyond it
  /// the realisation repeats up to a common phase shift of all harmonics); +infinity otherwise.
  double repeatLength() const;

  /// PSD realisation: the harmonic frequencies (rad/m) and, per channel, amplitudes (m) and phases (rad).
  const std::vector<double>& harmonicFrequencies() const { return Omega_; }
  const std::vector<double>& harmonicAmplitudes(IrregularityChannel c) const { return amplitude_[static_cast<int>(c)]; }
  const std::vector<double>& harmonicPhases(IrregularityChannel c) const { return phase_[static_cast<int>(c)]; }

 private:
  enum class Kind { kNone, kTable, kHarmonics };
  Kind kind_ = Kind::kNone;
  // Table: knots s_k, per channel values and Hermite slopes at the knots.
  std::vector<double> s_knots_;
  std::array<std::vector<double>, 4> knot_value_;
  std::array<std::vector<double>, 4> knot_slope_;
  // Harmonics: frequencies, per channel amplitudes and phases.
  std::vector<double> Omega_;
  std::array<std::vector<double>, 4> amplitude_;
  std::array<std::vector<double>, 4> phase_;
  double s_reference_ = 0.0;
  double d_Omega_ = 0.0;
  double wavelength_min_ = 0.0;
};

/// Accessors of one channel of a sample by index (0 alignment, 1 vertical level, 2 cross level, 3 gauge).
inline double& channelValue(IrregularitySample& x, int c) {
  return c == 0 ? x.alignment : c == 1 ? x.vertical_level : c == 2 ? x.cross_level : x.gauge;
}
inline double channelValue(const IrregularitySample& x, int c) {
  return c == 0 ? x.alignment : c == 1 ? x.vertical_level : c == 2 ? x.cross_level : x.gauge;
}

}  // namespace contact
}  // namespace rail
