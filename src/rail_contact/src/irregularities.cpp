// Track irregularities: CSV tables and seeded realisations of published PSDs.
#include "rail_contact/irregularities.hpp"
#include "rail_contact/format.hpp"

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <istream>
#include <limits>
#include <random>
#include <stdexcept>

namespace rail {
namespace contact {

namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------------------------------------------
// Published spectra.
//
// US FRA track classes 1-6: Garg, V.K., Dukkipati, R.V., "Dynamics of Railway Vehicle Systems",
// Academic Press, 1984 (analytical track-geometry spectra fitted to FRA measurements: Hamid, A., et al.,
// "Analytic descriptions of track geometry variations", FRA report DOT/FRA/ORD-83/03, 1983); the same
// table and formulas are reproduced in Zhai, W., "Vehicle-Track Coupled Dynamics: Theory and
// Applications", Springer, 2020, section 2 (track irregularity spectra). Units: A_v, A_a in cm^2 rad/m,
// Omega_s, Omega_c in rad/m, S in cm^2/(rad/m); k = 0.25.
//   vertical profile:       S_v = k A_v Omega_c^2 / (Omega^2 (Omega^2 + Omega_c^2))
//   alignment:              S_a = k A_a Omega_c^2 / (Omega^2 (Omega^2 + Omega_c^2))
//   cross level and gauge:  S_c = 4 k A_v Omega_c^2 / ((Omega^2 + Omega_c^2)(Omega^2 + Omega_s^2))
struct FraClass {
  double A_v, A_a, Omega_s, Omega_c;
};
constexpr FraClass kFraClasses[6] = {
    // A_v [cm^2 rad/m], A_a [cm^2 rad/m], Omega_s [rad/m], Omega_c [rad/m]  (Garg & Dukkipati 1984)
    {1.2107, 3.3634, 0.6046, 0.8245},  // class 1
    {1.0181, 1.2107, 0.9308, 0.8245},  // class 2
    {0.6816, 0.4128, 0.8520, 0.8245},  // class 3
    {0.5376, 0.3027, 1.1312, 0.8245},  // class 4
    {0.2095, 0.0762, 0.8209, 0.8245},  // class 5
    {0.0339, 0.0339, 0.4380, 0.8245},  // class 6
};
constexpr double kFraK = 0.25;       // safety factor k of the FRA formulas (same source)
constexpr double kCm2ToM2 = 1.0e-4;  // cm^2 -> m^2

// German high-speed / ERRI (ORE B176) low- and high-disturbance spectra, as given in Zhai (2020),
// section 2 (track irregularity spectra), from ORE B176 / DB measurements. Units: A in m^2 rad/m
// (m rad), Omega in rad/m, S_v, S_a, S_g in m^2/(rad/m), S_c (cross-level ANGLE) in rad^2/(rad/m):
//   vertical:    S_v = A_v Omega_c^2 / ((Omega^2 + Omega_r^2)(Omega^2 + Omega_c^2))
//   alignment:   S_a = A_a Omega_c^2 / ((Omega^2 + Omega_r^2)(Omega^2 + Omega_c^2))
//   cross level: S_c = (A_v / b^2) Omega_c^2 Omega^2 / ((Omega^2 + Omega_r^2)(Omega^2 + Omega_c^2)(Omega^2 +
//   Omega_s^2)) gauge:       S_g = A_g Omega_c^2 Omega^2 / ((Omega^2 + Omega_r^2)(Omega^2 + Omega_c^2)(Omega^2 +
//   Omega_s^2))
// with b = 0.75 m half the distance between the rolling circles.
struct GermanLevel {
  double A_v, A_a, A_g;
};
constexpr GermanLevel kGermanLow = {4.032e-7, 2.119e-7, 0.532e-7};   // low disturbance (Zhai 2020)
constexpr GermanLevel kGermanHigh = {10.80e-7, 6.125e-7, 1.032e-7};  // high disturbance (Zhai 2020)
constexpr double kGermanOmegaC = 0.8246;                             // rad/m (Zhai 2020)
constexpr double kGermanOmegaR = 0.0206;                             // rad/m (Zhai 2020)
constexpr double kGermanOmegaS = 0.4380;                             // rad/m (Zhai 2020)
constexpr double kGermanB = 0.75;                                    // m (Zhai 2020)

const char* const kChannelNames[4] = {"alignment", "vertical level", "cross level", "gauge"};

// Largest plausible magnitude of a tabulated irregularity (m): catches tables written in millimetres.
constexpr double kMaxPlausibleIrregularity = 0.1;

}  // namespace

PsdSpectrum psdSpectrumFromName(const std::string& name) {
  static const char* const kNames[8] = {"fra_class_1", "fra_class_2", "fra_class_3", "fra_class_4",
                                        "fra_class_5", "fra_class_6", "german_low",  "german_high"};
  for (int i = 0; i < 8; ++i)
    if (name == kNames[i]) return static_cast<PsdSpectrum>(i);
  std::string accepted;
  for (int i = 0; i < 8; ++i) accepted += (i ? ", " : "") + std::string(kNames[i]);
  throw std::runtime_error("irregularity PSD: unknown spectrum '" + name + "' (accepted: " + accepted + ")");
}

double psdValue(PsdSpectrum spectrum, IrregularityChannel channel, double Omega) {
  const double W2 = Omega * Omega;
  const int idx = static_cast<int>(spectrum);
  if (idx <= static_cast<int>(PsdSpectrum::kFraClass6)) {
    const FraClass& c = kFraClasses[idx];
    const double Wc2 = c.Omega_c * c.Omega_c;
    double s_cm2 = 0.0;
    switch (channel) {
      case IrregularityChannel::kVerticalLevel:
        s_cm2 = kFraK * c.A_v * Wc2 / (W2 * (W2 + Wc2));
        break;
      case IrregularityChannel::kAlignment:
        s_cm2 = kFraK * c.A_a * Wc2 / (W2 * (W2 + Wc2));
        break;
      case IrregularityChannel::kCrossLevel:
      case IrregularityChannel::kGauge:
        s_cm2 = 4.0 * kFraK * c.A_v * Wc2 / ((W2 + Wc2) * (W2 + c.Omega_s * c.Omega_s));
        break;
    }
    return s_cm2 * kCm2ToM2;
  }
  const GermanLevel& g = spectrum == PsdSpectrum::kGermanLow ? kGermanLow : kGermanHigh;
  const double Wc2 = kGermanOmegaC * kGermanOmegaC, Wr2 = kGermanOmegaR * kGermanOmegaR,
               Ws2 = kGermanOmegaS * kGermanOmegaS;
  switch (channel) {
    case IrregularityChannel::kVerticalLevel:
      return g.A_v * Wc2 / ((W2 + Wr2) * (W2 + Wc2));
    case IrregularityChannel::kAlignment:
      return g.A_a * Wc2 / ((W2 + Wr2) * (W2 + Wc2));
    case IrregularityChannel::kCrossLevel: {
      const double angle_psd = (g.A_v / (kGermanB * kGermanB)) * Wc2 * W2 / ((W2 + Wr2) * (W2 + Wc2) * (W2 + Ws2));
      const double base = 2.0 * kGermanB;  // height difference = angle * 2b
      return base * base * angle_psd;
    }
    case IrregularityChannel::kGauge:
      return g.A_g * Wc2 * W2 / ((W2 + Wr2) * (W2 + Wc2) * (W2 + Ws2));
  }
  return 0.0;
}

// ---------------------------------------------------------------------------------------------------
// CSV table.

Irregularities Irregularities::fromCsvFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open irregularity file");
  return fromCsvStream(in, path);
}

Irregularities Irregularities::fromCsvStream(std::istream& in, const std::string& name) {
  Irregularities out;
  out.kind_ = Kind::kTable;
  std::string line;
  int line_no = 0;
  bool header_allowed = true;
  while (std::getline(in, line)) {
    ++line_no;
    const std::size_t hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    const std::string where = name + ":" + std::to_string(line_no) + ": ";
    // Split on commas.
    std::vector<std::string> fields;
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = line.find(',', start);
      fields.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
    double v[5];
    bool numeric = fields.size() == 5;
    int bad_col = -1;
    if (numeric) {
      for (int c = 0; c < 5; ++c) {
        const std::string& f = fields[c];
        const char* b = f.c_str();
        char* end = nullptr;
        v[c] = std::strtod(b, &end);
        while (end && (*end == ' ' || *end == '\t')) ++end;
        if (end == b || *end != '\0' || f.find_first_not_of(" \t") == std::string::npos) {
          numeric = false;
          bad_col = c;
          break;
        }
      }
    }
    if (!numeric) {
      const bool has_letter = std::any_of(line.begin(), line.end(), [](unsigned char ch) { return std::isalpha(ch); });
      if (header_allowed && has_letter && out.s_knots_.empty()) {  // one header line of column names
        header_allowed = false;
        continue;
      }
      if (fields.size() != 5)
        throw std::runtime_error(where +
                                 "expected 5 comma-separated columns (s, alignment, vertical level, cross "
                                 "level, gauge), got " +
                                 std::to_string(fields.size()));
      const char* col_name = bad_col == 0 ? "s" : kChannelNames[bad_col - 1];
      throw std::runtime_error(where + "column " + std::to_string(bad_col + 1) + " (" + col_name + "): cannot read '" +
                               fields[bad_col] + "' as a number");
    }
    header_allowed = false;
    for (int c = 0; c < 5; ++c) {
      if (!std::isfinite(v[c])) {
        const char* col_name = c == 0 ? "s" : kChannelNames[c - 1];
        throw std::runtime_error(where + "column " + std::to_string(c + 1) + " (" + col_name +
                                 ") = " + formatNumber(v[c]) + " is not finite");
      }
    }
    if (!out.s_knots_.empty() && !(v[0] > out.s_knots_.back()))
      throw std::runtime_error(where + "s not increasing (" + formatNumber(v[0]) + " after " +
                               formatNumber(out.s_knots_.back()) + ")");
    for (int c = 1; c < 5; ++c) {
      if (std::abs(v[c]) > kMaxPlausibleIrregularity)
        throw std::runtime_error(where + kChannelNames[c - 1] + " = " + formatNumber(v[c]) +
                                 " m is not a plausible irregularity (|value| > " +
                                 formatNumber(kMaxPlausibleIrregularity) + " m; values must be in metres)");
    }
    out.s_knots_.push_back(v[0]);
    for (int c = 0; c < 4; ++c) out.knot_value_[c].push_back(v[c + 1]);
  }
  if (out.s_knots_.size() < 2)
    throw std::runtime_error(name + ": " + std::to_string(out.s_knots_.size()) +
                             " data rows; an irregularity table needs at least 2");
  // Hermite slopes: three-point (second-order) differences inside, secants at the ends.
  const std::size_t n = out.s_knots_.size();
  const std::vector<double>& s = out.s_knots_;
  for (int c = 0; c < 4; ++c) {
    const std::vector<double>& f = out.knot_value_[c];
    std::vector<double>& m = out.knot_slope_[c];
    m.resize(n);
    m[0] = (f[1] - f[0]) / (s[1] - s[0]);
    m[n - 1] = (f[n - 1] - f[n - 2]) / (s[n - 1] - s[n - 2]);
    for (std::size_t k = 1; k + 1 < n; ++k) {
      const double h0 = s[k] - s[k - 1], h1 = s[k + 1] - s[k];
      m[k] = (h0 * h0 * (f[k + 1] - f[k]) + h1 * h1 * (f[k] - f[k - 1])) / (h0 * h1 * (h0 + h1));
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------
// PSD realisation.

Irregularities Irregularities::fromPsd(const PsdRealisationSpec& spec) {
  if (!(spec.wavelength_min > 0.0) || !std::isfinite(spec.wavelength_min))
    throw std::runtime_error("irregularity PSD: wavelength_min = " + formatNumber(spec.wavelength_min) +
                             " m must be positive");
  if (!(spec.wavelength_max > spec.wavelength_min) || !std::isfinite(spec.wavelength_max))
    throw std::runtime_error("irregularity PSD: wavelength_max = " + formatNumber(spec.wavelength_max) +
                             " m must exceed wavelength_min = " + formatNumber(spec.wavelength_min) + " m");
  if (spec.harmonics < 1 || spec.harmonics > 1000000)
    throw std::runtime_error("irregularity PSD: harmonics = " + std::to_string(spec.harmonics) +
                             " must be in [1, 1000000]");
  if (!std::isfinite(spec.s_reference))
    throw std::runtime_error("irregularity PSD: s_reference = " + formatNumber(spec.s_reference) + " is not finite");
  Irregularities out;
  out.kind_ = Kind::kHarmonics;
  out.s_reference_ = spec.s_reference;
  out.wavelength_min_ = spec.wavelength_min;
  const int N = spec.harmonics;
  const double Omega_min = 2.0 * kPi / spec.wavelength_max;
  const double Omega_max = 2.0 * kPi / spec.wavelength_min;
  out.d_Omega_ = (Omega_max - Omega_min) / N;
  out.Omega_.resize(N);
  for (int k = 0; k < N; ++k) out.Omega_[k] = Omega_min + (k + 0.5) * out.d_Omega_;
  // Phases: 53 random bits of each mt19937_64 output scaled to [0, 1) (exact in double), channel by
  // channel in the order alignment, vertical level, cross level, gauge.
  std::mt19937_64 engine(spec.seed);
  const bool enabled[4] = {spec.alignment, spec.vertical_level, spec.cross_level, spec.gauge};
  const IrregularityChannel channels[4] = {IrregularityChannel::kAlignment, IrregularityChannel::kVerticalLevel,
                                           IrregularityChannel::kCrossLevel, IrregularityChannel::kGauge};
  for (int c = 0; c < 4; ++c) {
    out.phase_[c].resize(N);
    out.amplitude_[c].assign(N, 0.0);
    for (int k = 0; k < N; ++k) {
      const double u = static_cast<double>(engine() >> 11) * 0x1.0p-53;
      out.phase_[c][k] = 2.0 * kPi * u;
      if (enabled[c])
        out.amplitude_[c][k] = std::sqrt(2.0 * psdValue(spec.spectrum, channels[c], out.Omega_[k]) * out.d_Omega_);
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------------
// Evaluation.

namespace {
std::atomic<long long> g_stations_evaluated{0};  // Irregularities::stationsEvaluated()
}  // namespace

long long Irregularities::stationsEvaluated() { return g_stations_evaluated.load(std::memory_order_relaxed); }

void Irregularities::evaluate(double s, IrregularityState& out) const {
  g_stations_evaluated.fetch_add(1, std::memory_order_relaxed);
  out = IrregularityState();
  if (kind_ == Kind::kTable) {
    const std::vector<double>& sk = s_knots_;
    if (s <= sk.front() || s >= sk.back()) {  // held constant beyond the table
      const std::size_t k = s <= sk.front() ? 0 : sk.size() - 1;
      for (int c = 0; c < 4; ++c) channelValue(out.value, c) = knot_value_[c][k];
      return;
    }
    const std::size_t k = static_cast<std::size_t>(std::upper_bound(sk.begin(), sk.end(), s) - sk.begin()) - 1;
    const double h = sk[k + 1] - sk[k];
    const double t = (s - sk[k]) / h, t2 = t * t, t3 = t2 * t;
    const double h00 = 2 * t3 - 3 * t2 + 1, h10 = t3 - 2 * t2 + t, h01 = -2 * t3 + 3 * t2, h11 = t3 - t2;
    const double d00 = 6 * t2 - 6 * t, d10 = 3 * t2 - 4 * t + 1, d01 = -d00, d11 = 3 * t2 - 2 * t;
    const double e00 = 12 * t - 6, e10 = 6 * t - 4, e01 = -e00, e11 = 6 * t - 2;
    for (int c = 0; c < 4; ++c) {
      const double f0 = knot_value_[c][k], f1 = knot_value_[c][k + 1];
      const double m0 = knot_slope_[c][k], m1 = knot_slope_[c][k + 1];
      channelValue(out.value, c) = h00 * f0 + h10 * h * m0 + h01 * f1 + h11 * h * m1;
      channelValue(out.d_ds, c) = (d00 * f0 + d01 * f1) / h + d10 * m0 + d11 * m1;
      channelValue(out.d2_ds2, c) = (e00 * f0 + e01 * f1) / (h * h) + (e10 * m0 + e11 * m1) / h;
    }
  } else if (kind_ == Kind::kHarmonics) {
    const double x = s - s_reference_;
    for (int c = 0; c < 4; ++c) {
      const std::vector<double>& a = amplitude_[c];
      const std::vector<double>& ph = phase_[c];
      double v = 0, d1 = 0, d2 = 0;
      for (std::size_t k = 0; k < Omega_.size(); ++k) {
        if (a[k] == 0.0) continue;
        const double W = Omega_[k], arg = W * x + ph[k];
        const double cs = std::cos(arg), sn = std::sin(arg);
        v += a[k] * cs;
        d1 -= a[k] * W * sn;
        d2 -= a[k] * W * W * cs;
      }
      channelValue(out.value, c) = v;
      channelValue(out.d_ds, c) = d1;
      channelValue(out.d2_ds2, c) = d2;
    }
  }
}

void Irregularities::sampleUniform(double s0, double h, std::vector<IrregularityState>& out) const {
  const std::size_t n = out.size();
  if (kind_ != Kind::kHarmonics) {
    for (std::size_t i = 0; i < n; ++i) evaluate(s0 + static_cast<double>(i) * h, out[i]);
    return;
  }
  g_stations_evaluated.fetch_add(static_cast<long long>(n), std::memory_order_relaxed);
  for (std::size_t i = 0; i < n; ++i) out[i] = IrregularityState();
  constexpr std::size_t kAnchor = 256;  // exact cos/sin every kAnchor stations bounds the recurrence drift
  const double x0 = s0 - s_reference_;
  for (int c = 0; c < 4; ++c) {
    const std::vector<double>& a = amplitude_[c];
    const std::vector<double>& ph = phase_[c];
    for (std::size_t k = 0; k < Omega_.size(); ++k) {
      if (a[k] == 0.0) continue;
      const double W = Omega_[k];
      const double cw = std::cos(W * h), sw = std::sin(W * h);
      double cs = 0.0, sn = 0.0;
      for (std::size_t i = 0; i < n; ++i) {
        if (i % kAnchor == 0) {
          const double arg = W * (x0 + static_cast<double>(i) * h) + ph[k];
          cs = std::cos(arg);
          sn = std::sin(arg);
        }
        channelValue(out[i].value, c) += a[k] * cs;
        channelValue(out[i].d_ds, c) -= a[k] * W * sn;
        channelValue(out[i].d2_ds2, c) -= a[k] * W * W * cs;
        const double cs_next = cs * cw - sn * sw;  // cos(arg + W h)
        sn = sn * cw + cs * sw;                    // sin(arg + W h)
        cs = cs_next;
      }
    }
  }
}

double Irregularities::shortestWavelength() const {
  if (kind_ == Kind::kHarmonics) return wavelength_min_;
  if (kind_ == Kind::kTable) {
    double d = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k + 1 < s_knots_.size(); ++k) d = std::min(d, s_knots_[k + 1] - s_knots_[k]);
    return 2.0 * d;
  }
  return std::numeric_limits<double>::infinity();
}

double Irregularities::repeatLength() const {
  if (kind_ == Kind::kHarmonics) return 2.0 * kPi / d_Omega_;
  return std::numeric_limits<double>::infinity();
}

}  // namespace contact
}  // namespace rail
