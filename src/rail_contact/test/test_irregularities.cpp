// Tests of the irregularity sources: published PSD values, seeded realisations (reproducibility,
// band variance, spectral shape, ensemble statistics) and the CSV table reader.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "rail_contact/irregularities.hpp"

namespace rc = rail::contact;
using Ch = rc::IrregularityChannel;

namespace {

constexpr double kPi = 3.14159265358979323846;

rc::PsdRealisationSpec psdSpec(rc::PsdSpectrum sp, std::uint64_t seed, int harmonics = 1024) {
  rc::PsdRealisationSpec p;
  p.spectrum = sp;
  p.wavelength_min = 2.0;
  p.wavelength_max = 60.0;
  p.seed = seed;
  p.harmonics = harmonics;
  return p;
}

std::string csvError(const std::string& text, const std::string& name = "t.csv") {
  std::istringstream in(text);
  try {
    rc::Irregularities::fromCsvStream(in, name);
  } catch (const std::runtime_error& ex) {
    return ex.what();
  }
  return "no exception";
}

}  // namespace

// PSD values against the published formulas evaluated by hand (independently of the library) at one
// frequency each; relative tolerance 1e-9 (the hand values carry 13+ digits).
//  FRA class 6 profile, Omega = 1: 0.25 * 0.0339 * 0.8245^2 / (1 * (1 + 0.8245^2)) cm^2 = 3.4297573e-7 m^2
//  FRA class 4 alignment, Omega = 0.5: 0.25 * 0.3027 * 0.8245^2 / (0.25 (0.25 + 0.8245^2)) cm^2
//  FRA class 4 cross level, Omega = 0.5: 4 * 0.25 * 0.5376 * 0.8245^2 / ((0.25 + 0.8245^2)(0.25 + 1.1312^2))
//  German low vertical, Omega = 1: 4.032e-7 * 0.8246^2 / ((1 + 0.0206^2)(1 + 0.8246^2))
//  German high cross level (height, base 1.5 m), Omega = 0.3:
//    1.5^2 (10.80e-7 / 0.75^2) 0.8246^2 0.09 / ((0.09 + 0.0206^2)(0.09 + 0.8246^2)(0.09 + 0.438^2))
//  German high gauge, Omega = 0.3: 1.032e-7 0.8246^2 0.09 / (same denominator)
TEST(IrregularityPsd, ValuesMatchPublishedFormulas) {
  auto rel = [](double got, double want) { return std::abs(got - want) / want; };
  EXPECT_LT(rel(rc::psdValue(rc::PsdSpectrum::kFraClass6, Ch::kVerticalLevel, 1.0), 3.429757269502728e-07), 1e-9);
  EXPECT_LT(rel(rc::psdValue(rc::PsdSpectrum::kFraClass4, Ch::kAlignment, 0.5), 2.2131155124447432e-05), 1e-9);
  EXPECT_LT(rel(rc::psdValue(rc::PsdSpectrum::kFraClass4, Ch::kCrossLevel, 0.5), 2.569621932783255e-05), 1e-9);
  EXPECT_LT(rel(rc::psdValue(rc::PsdSpectrum::kGermanLow, Ch::kVerticalLevel, 1.0), 1.6312579868999215e-07), 1e-9);
  EXPECT_LT(rel(rc::psdValue(rc::PsdSpectrum::kGermanHigh, Ch::kCrossLevel, 0.3), 1.3472481795017011e-05), 1e-9);
  EXPECT_LT(rel(rc::psdValue(rc::PsdSpectrum::kGermanHigh, Ch::kGauge, 0.3), 3.218426206587396e-07), 1e-9);
}

TEST(IrregularityPsd, SpectrumNames) {
  EXPECT_EQ(rc::psdSpectrumFromName("fra_class_4"), rc::PsdSpectrum::kFraClass4);
  EXPECT_EQ(rc::psdSpectrumFromName("german_high"), rc::PsdSpectrum::kGermanHigh);
  try {
    rc::psdSpectrumFromName("fra_class_7");
    FAIL();
  } catch (const std::runtime_error& ex) {
    EXPECT_NE(std::string(ex.what()).find("'fra_class_7'"), std::string::npos);
    EXPECT_NE(std::string(ex.what()).find("german_low"), std::string::npos);
  }
}

TEST(IrregularityPsd, SameSeedSameSignalDifferentSeedDifferent) {
  const auto a = rc::Irregularities::fromPsd(psdSpec(rc::PsdSpectrum::kFraClass5, 42));
  const auto b = rc::Irregularities::fromPsd(psdSpec(rc::PsdSpectrum::kFraClass5, 42));
  const auto c = rc::Irregularities::fromPsd(psdSpec(rc::PsdSpectrum::kFraClass5, 43));
  double max_diff_c = 0.0, rms = 0.0;
  const int n = 500;
  for (int i = 0; i < n; ++i) {
    const double s = 0.37 * i;
    rc::IrregularityState xa, xb, xc;
    a.evaluate(s, xa);
    b.evaluate(s, xb);
    c.evaluate(s, xc);
    for (int ch = 0; ch < 4; ++ch) EXPECT_EQ(rc::channelValue(xa.value, ch), rc::channelValue(xb.value, ch));
    max_diff_c = std::max(max_diff_c, std::abs(xa.value.vertical_level - xc.value.vertical_level));
    rms += xa.value.vertical_level * xa.value.vertical_level / n;
  }
  // Independent realisations differ by the order of the signal itself, not by round-off.
  EXPECT_GT(max_diff_c, 0.5 * std::sqrt(rms));
}

// Reproducibility across standard libraries: the phases use only the raw output of std::mt19937_64,
// whose sequence the C++ standard fixes ([rand.predef]: the 10000th output of a default-constructed
// engine, seed 5489, is 9981545732273789042). The first phase must be 2 pi (first output >> 11) / 2^53.
TEST(IrregularityPsd, PhasesComeFromTheStandardEngineBits) {
  std::mt19937_64 reference(5489u);
  const std::uint64_t first = reference();
  for (int i = 2; i < 10000; ++i) reference();
  ASSERT_EQ(reference(), 9981545732273789042ull) << "mt19937_64 deviates from [rand.predef]";
  const auto r = rc::Irregularities::fromPsd(psdSpec(rc::PsdSpectrum::kFraClass3, 5489u, 16));
  EXPECT_EQ(r.harmonicPhases(Ch::kAlignment)[0], 2.0 * kPi * static_cast<double>(first >> 11) * 0x1.0p-53);
}

namespace {

// Closed-form band integrals (partial fractions) of the published PSDs, in m^2.
// FRA profile/alignment: k A Wc^2 / (W^2 (W^2 + Wc^2)) = k A (1/W^2 - 1/(W^2 + Wc^2)).
double fraProfileIntegral(double kA, double Wc, double W1, double W2) {
  auto F = [&](double W) { return kA * (-1.0 / W - std::atan(W / Wc) / Wc); };
  return F(W2) - F(W1);
}
// Its first moment in W^2: W^2 S = k A Wc^2 / (W^2 + Wc^2).
double fraProfileSlopeIntegral(double kA, double Wc, double W1, double W2) {
  auto F = [&](double W) { return kA * Wc * std::atan(W / Wc); };
  return F(W2) - F(W1);
}
// Integral of 1 / prod_i (W^2 + q_i) for distinct q_i, times W^(2 p) (p = 0 or 1), by partial fractions in
// u = W^2: u^p / prod (u + q_i) = sum_i r_i / (u + q_i), r_i = (-q_i)^p / prod_{j != i} (q_j - q_i).
double rationalIntegral(const std::vector<double>& q, int p, double W1, double W2) {
  double total = 0.0;
  for (std::size_t i = 0; i < q.size(); ++i) {
    double r = std::pow(-q[i], p);
    for (std::size_t j = 0; j < q.size(); ++j)
      if (j != i) r /= (q[j] - q[i]);
    const double a = std::sqrt(q[i]);
    total += r * (std::atan(W2 / a) - std::atan(W1 / a)) / a;
  }
  return total;
}

struct Moments {
  double mean_square = 0, slope_mean_square = 0;
};

// Mean square of a channel and of its slope over one period L = 2 pi / dOmega of the harmonics'
// difference frequencies, from M uniform samples (spacing L / M < lambda_min / 10).
Moments sampleMoments(const rc::Irregularities& r, Ch ch) {
  const double L = r.repeatLength();
  const int M = static_cast<int>(std::ceil(L / 0.2));
  std::vector<rc::IrregularityState> x(M);
  r.sampleUniform(0.0, L / M, x);
  Moments m;
  for (const auto& q : x) {
    const double v = rc::channelValue(q.value, static_cast<int>(ch)),
                 d = rc::channelValue(q.d_ds, static_cast<int>(ch));
    m.mean_square += v * v / M;
    m.slope_mean_square += d * d / M;
  }
  return m;
}

// Standard deviation of (mean square - sum a_k^2 / 2) over the random phases, for M samples over one
// period L = M ds. x^2 = 1/2 sum_jk a_j a_k [cos((W_j - W_k) s + phi_j - phi_k) + cos((W_j + W_k) s + phi_j + phi_k)].
// The difference-frequency terms (j != k) average to exactly zero over the period (roots of unity); the
// sum-frequency terms average to a_j a_k eps_jk cos(phi_j + phi_k + ...), |eps_jk| <= 1 / (M |sin((W_j + W_k) ds /
// 2)|). With independent uniform phases these terms are uncorrelated with zero mean, so their sum has standard
// deviation sqrt(sum_{j<k} (a_j a_k eps_jk)^2 + sum_j (a_j^2 eps_jj / 2)^2). slope: amplitudes a_k W_k.
double crossTermSigma(const rc::Irregularities& r, Ch ch, bool slope) {
  const std::vector<double>& W = r.harmonicFrequencies();
  const std::vector<double>& a = r.harmonicAmplitudes(ch);
  const double L = r.repeatLength();
  const int M = static_cast<int>(std::ceil(L / 0.2));
  const double ds = L / M;
  double var = 0.0;
  for (std::size_t j = 0; j < W.size(); ++j)
    for (std::size_t k = j; k < W.size(); ++k) {
      const double aj = slope ? a[j] * W[j] : a[j], ak = slope ? a[k] * W[k] : a[k];
      const double eps = 1.0 / (M * std::abs(std::sin(0.5 * (W[j] + W[k]) * ds)));
      const double term = (j == k ? 0.5 : 1.0) * aj * ak * eps;
      var += term * term;
    }
  return std::sqrt(var);
}

double halfSumSquares(const rc::Irregularities& r, Ch ch, bool slope) {
  double s = 0.0;
  const std::vector<double>& W = r.harmonicFrequencies();
  const std::vector<double>& a = r.harmonicAmplitudes(ch);
  for (std::size_t k = 0; k < W.size(); ++k) s += 0.5 * a[k] * a[k] * (slope ? W[k] * W[k] : 1.0);
  return s;
}

}  // namespace

// Sample variance of a realisation over a long track (one period of the difference frequencies, ~2 km)
// against the PSD integrated over the band in closed form. Two steps, each with its own tolerance:
//  (1) sample mean square vs the realisation's discrete variance sum a_k^2 / 2: within 5 standard
//      deviations of the sum-frequency cross terms (crossTermSigma above; the only deviation for a sum of
//      harmonics with random phases over a full period), a statistical tolerance of ~1 % of the variance;
//  (2) sum a_k^2 / 2 = sum S(W_k) dW (midpoint rule) vs the closed-form integral: 1e-3 relative; the
//      midpoint error is ~ (dW / W_min)^2 / 24 * 3 ~ 1e-4 at the band's low end (dW / W_min ~ 0.03).
// The slope variance (integral of W^2 S) checks the distribution over frequency, not just the total.
TEST(IrregularityPsd, BandVarianceMatchesIntegratedPsd) {
  const double W1 = 2 * kPi / 60.0, W2 = 2 * kPi / 2.0;
  {
    const auto r = rc::Irregularities::fromPsd(psdSpec(rc::PsdSpectrum::kFraClass4, 11));
    const double kA_v = 0.25 * 0.5376e-4, kA_a = 0.25 * 0.3027e-4, Wc = 0.8245, Ws = 1.1312;  // class 4
    struct Case {
      Ch ch;
      double variance, slope_variance;
    };
    const Case cases[] = {
        {Ch::kVerticalLevel, fraProfileIntegral(kA_v, Wc, W1, W2), fraProfileSlopeIntegral(kA_v, Wc, W1, W2)},
        {Ch::kAlignment, fraProfileIntegral(kA_a, Wc, W1, W2), fraProfileSlopeIntegral(kA_a, Wc, W1, W2)},
        {Ch::kCrossLevel, 4 * kA_v * Wc * Wc * rationalIntegral({Wc * Wc, Ws * Ws}, 0, W1, W2),
         4 * kA_v * Wc * Wc * rationalIntegral({Wc * Wc, Ws * Ws}, 1, W1, W2)},
    };
    for (const Case& c : cases) {
      const Moments m = sampleMoments(r, c.ch);
      EXPECT_NEAR(m.mean_square, halfSumSquares(r, c.ch, false), 5.0 * crossTermSigma(r, c.ch, false));
      EXPECT_NEAR(m.slope_mean_square, halfSumSquares(r, c.ch, true), 5.0 * crossTermSigma(r, c.ch, true));
      EXPECT_NEAR(halfSumSquares(r, c.ch, false), c.variance, 1e-3 * c.variance);
      EXPECT_NEAR(halfSumSquares(r, c.ch, true), c.slope_variance, 1e-3 * c.slope_variance);
      // The statistical tolerance itself must be small for this to be a test of the variance.
      EXPECT_LT(5.0 * crossTermSigma(r, c.ch, false), 0.05 * c.variance);
    }
  }
  {
    const auto r = rc::Irregularities::fromPsd(psdSpec(rc::PsdSpectrum::kGermanHigh, 12));
    const double Wc2 = 0.8246 * 0.8246, Wr2 = 0.0206 * 0.0206, Ws2 = 0.438 * 0.438;
    const double var_v = 10.80e-7 * Wc2 * rationalIntegral({Wr2, Wc2}, 0, W1, W2);
    const double var_g = 1.032e-7 * Wc2 * rationalIntegral({Wr2, Wc2, Ws2}, 1, W1, W2);
    const double var_c = 4.0 * 10.80e-7 * Wc2 * rationalIntegral({Wr2, Wc2, Ws2}, 1, W1, W2);  // (2b)^2 A_v/b^2
    const std::pair<Ch, double> cases[] = {{Ch::kVerticalLevel, var_v}, {Ch::kGauge, var_g}, {Ch::kCrossLevel, var_c}};
    for (const auto& c : cases) {
      const Moments m = sampleMoments(r, c.first);
      EXPECT_NEAR(m.mean_square, halfSumSquares(r, c.first, false), 5.0 * crossTermSigma(r, c.first, false));
      EXPECT_NEAR(halfSumSquares(r, c.first, false), c.second, 1e-3 * c.second);
      EXPECT_LT(5.0 * crossTermSigma(r, c.first, false), 0.05 * c.second);
    }
  }
}

// Ensemble statistics: the value at a fixed station over 2000 seeds has variance sum a_k^2 / 2. The
// sample variance of n draws of a near-Gaussian variable has relative standard deviation sqrt(2/(n-1))
// (a sum of random-phase cosines has negative excess kurtosis, so this is conservative): 4 sigma = 12.7 %.
TEST(IrregularityPsd, EnsembleVarianceAtAStation) {
  const int n = 2000;
  double sum = 0, sum2 = 0, expected = 0;
  for (int seed = 1; seed <= n; ++seed) {
    const auto r = rc::Irregularities::fromPsd(psdSpec(rc::PsdSpectrum::kFraClass2, 1000 + seed, 256));
    if (seed == 1) expected = halfSumSquares(r, Ch::kAlignment, false);
    rc::IrregularityState x;
    r.evaluate(123.4, x);
    sum += x.value.alignment;
    sum2 += x.value.alignment * x.value.alignment;
  }
  const double mean = sum / n, var = (sum2 - n * mean * mean) / (n - 1);
  EXPECT_NEAR(var, expected, 4.0 * std::sqrt(2.0 / (n - 1)) * expected);
  EXPECT_NEAR(mean, 0.0, 4.0 * std::sqrt(expected / n));  // 4 standard errors of the mean
}

// German high and low spectra have the same shape: with the same seed the vertical signals are in the
// exact ratio sqrt(A_v,high / A_v,low) = sqrt(10.80 / 4.032) (round-off tolerance 1e-12 relative).
TEST(IrregularityPsd, GermanHighIsScaledLowForSameSeed) {
  const auto lo = rc::Irregularities::fromPsd(psdSpec(rc::PsdSpectrum::kGermanLow, 5));
  const auto hi = rc::Irregularities::fromPsd(psdSpec(rc::PsdSpectrum::kGermanHigh, 5));
  for (double s : {0.0, 17.3, 250.0}) {
    rc::IrregularityState a, b;
    lo.evaluate(s, a);
    hi.evaluate(s, b);
    EXPECT_NEAR(b.value.vertical_level, std::sqrt(10.80 / 4.032) * a.value.vertical_level,
                1e-12 * std::abs(b.value.vertical_level) + 1e-18);
  }
}

// A channel switched off is zero and does not change the others (phases are drawn regardless).
TEST(IrregularityPsd, ChannelSwitchedOffLeavesOthersUnchanged) {
  auto p = psdSpec(rc::PsdSpectrum::kFraClass3, 9);
  const auto all = rc::Irregularities::fromPsd(p);
  p.gauge = false;
  p.alignment = false;
  const auto some = rc::Irregularities::fromPsd(p);
  rc::IrregularityState a, b;
  all.evaluate(31.0, a);
  some.evaluate(31.0, b);
  EXPECT_EQ(b.value.gauge, 0.0);
  EXPECT_EQ(b.value.alignment, 0.0);
  EXPECT_EQ(a.value.vertical_level, b.value.vertical_level);
  EXPECT_EQ(a.value.cross_level, b.value.cross_level);
}

// Derivatives of a realisation: analytic d/ds and d2/ds2 against central differences (step 1e-3 m;
// truncation ds^2/6 |x'''| ~ 1e-6 * W_max^3 * rms ~ 1e-8 relative), and the bulk sampler (rotation
// recurrence) against direct evaluation: 1e-12 relative to the signal's rms.
TEST(IrregularityPsd, DerivativesAndBulkSamplerAreConsistent) {
  const auto r = rc::Irregularities::fromPsd(psdSpec(rc::PsdSpectrum::kFraClass4, 3, 512));
  const double rms = std::sqrt(halfSumSquares(r, Ch::kVerticalLevel, false));
  const double rms1 = std::sqrt(halfSumSquares(r, Ch::kVerticalLevel, true));
  const double ds = 1e-3;
  for (double s : {3.3, 77.0}) {
    rc::IrregularityState a, b, c;
    r.evaluate(s - ds, a);
    r.evaluate(s + ds, b);
    r.evaluate(s, c);
    EXPECT_NEAR((b.value.vertical_level - a.value.vertical_level) / (2 * ds), c.d_ds.vertical_level, 1e-5 * rms1);
    EXPECT_NEAR((b.d_ds.vertical_level - a.d_ds.vertical_level) / (2 * ds), c.d2_ds2.vertical_level,
                1e-5 * rms1 * 2 * kPi / 2.0);
  }
  std::vector<rc::IrregularityState> bulk(1000);
  r.sampleUniform(-5.0, 0.1, bulk);
  for (int i : {0, 255, 256, 700, 999}) {
    rc::IrregularityState x;
    r.evaluate(-5.0 + 0.1 * i, x);
    EXPECT_NEAR(bulk[i].value.vertical_level, x.value.vertical_level, 1e-12 * rms);
    EXPECT_NEAR(bulk[i].d_ds.cross_level, x.d_ds.cross_level, 1e-11 * rms1 * 4);
  }
}

TEST(IrregularityPsd, BadSpecThrows) {
  auto p = psdSpec(rc::PsdSpectrum::kFraClass1, 1);
  p.wavelength_min = 0.0;
  EXPECT_THROW(rc::Irregularities::fromPsd(p), std::runtime_error);
  p.wavelength_min = 70.0;  // above wavelength_max
  EXPECT_THROW(rc::Irregularities::fromPsd(p), std::runtime_error);
  p = psdSpec(rc::PsdSpectrum::kFraClass1, 1, 0);
  EXPECT_THROW(rc::Irregularities::fromPsd(p), std::runtime_error);
}

// Table interpolation: three-point slopes are exact for quadratics and cubic Hermite reproduces a
// quadratic exactly when its knot slopes are exact, i.e. on every interval not touching the end knots
// (whose slopes are secants). Tolerance: round-off (1e-15 m on values of ~1e-3 m).
TEST(IrregularityTable, InteriorIntervalsReproduceAQuadratic) {
  auto f = [](double s) { return 1e-3 + 2e-4 * s - 1e-5 * s * s; };
  auto df = [](double s) { return 2e-4 - 2e-5 * s; };
  const double knots[] = {0.0, 0.7, 1.5, 1.9, 3.0, 4.2, 5.0};
  std::ostringstream csv;
  csv << "# s, alignment, vertical level, cross level, gauge\n\n";
  csv.precision(17);
  for (double s : knots) csv << s << ", " << f(s) << ", 0, " << -f(s) << ", 0.001\n";
  std::istringstream in(csv.str());
  const auto r = rc::Irregularities::fromCsvStream(in, "quad.csv");
  for (double s : {0.9, 1.5, 2.5, 3.9}) {
    rc::IrregularityState x;
    r.evaluate(s, x);
    EXPECT_NEAR(x.value.alignment, f(s), 1e-15);
    EXPECT_NEAR(x.d_ds.alignment, df(s), 1e-14);
    EXPECT_NEAR(x.d2_ds2.alignment, -2e-5, 1e-13);
    EXPECT_NEAR(x.value.cross_level, -f(s), 1e-15);
    EXPECT_NEAR(x.value.gauge, 0.001, 1e-15);
  }
  rc::IrregularityState x;
  r.evaluate(-3.0, x);  // held at the first row
  EXPECT_EQ(x.value.alignment, f(0.0));
  EXPECT_EQ(x.d_ds.alignment, 0.0);
  r.evaluate(9.0, x);  // held at the last row
  EXPECT_EQ(x.value.cross_level, -f(5.0));
  EXPECT_DOUBLE_EQ(r.shortestWavelength(), 2 * 0.4);
}

TEST(IrregularityTable, ReaderErrorsNameFileAndLine) {
  EXPECT_NE(csvError("s,a,v,c,g\n0,0,0,0,0\n1.0, 0.001, 0, 0\n").find("t.csv:3: expected 5 comma-separated columns"),
            std::string::npos);
  EXPECT_NE(csvError("# comment\n0,0,0,0,0\n2,0,0,0,0\n\n1,0,0,0,0\n").find("t.csv:5: s not increasing (1 after 2)"),
            std::string::npos);
  EXPECT_NE(csvError("0,0,0,0,0\n1,0,abc,0,0\n").find("t.csv:2: column 3 (vertical level): cannot read 'abc'"),
            std::string::npos);
  EXPECT_NE(csvError("0,0,0,0,0\n1,0,0,3.5,0\n").find("t.csv:2: cross level = 3.5 m is not a plausible irregularity"),
            std::string::npos);
  EXPECT_NE(csvError("0,0,0,0,0\n1,0,0,0,nan\n").find("t.csv:2: column 5 (gauge) = nan is not finite"),
            std::string::npos);
  EXPECT_NE(csvError("0,0,0,0,0\n").find("t.csv: 1 data rows; an irregularity table needs at least 2"),
            std::string::npos);
  EXPECT_NE(csvError("0,0,0,0,0\ns,a,v,c,g\n").find("t.csv:2: column 1 (s): cannot read 's'"), std::string::npos);
  try {
    rc::Irregularities::fromCsvFile("/nonexistent/dir/irr.csv");
    FAIL();
  } catch (const std::runtime_error& ex) {
    EXPECT_NE(std::string(ex.what()).find("/nonexistent/dir/irr.csv: cannot open"), std::string::npos);
  }
}

TEST(IrregularityTable, ReadsAFile) {
  const std::string path = ::testing::TempDir() + "irregularities_test.csv";
  {
    std::ofstream out(path);
    out << "s,alignment,level,cross_level,gauge\r\n0,0.001,0.002,0.003,0.004\r\n10,0.001,0.002,0.003,0.004\r\n";
  }
  const auto r = rc::Irregularities::fromCsvFile(path);
  rc::IrregularityState x;
  r.evaluate(5.0, x);
  EXPECT_NEAR(x.value.alignment, 0.001, 1e-18);
  EXPECT_NEAR(x.value.vertical_level, 0.002, 1e-18);
  EXPECT_NEAR(x.value.cross_level, 0.003, 1e-18);
  EXPECT_NEAR(x.value.gauge, 0.004, 1e-18);
  std::remove(path.c_str());
}
