// The Illinois method (regula falsi that halves the value kept at an end which stays twice in a row, so
// that both ends move): one bracket and its update, for the one-dimensional root searches of the contact.
#pragma once

namespace rail::contact {

struct IllinoisBracket {
  double a = 0.0, g_a = 0.0;  // one end and g there
  double b = 0.0, g_b = 0.0;  // the other end, g of the opposite sign
  int side = 0;               // which end the last update replaced: -1 b, +1 a

  // The secant's zero between the ends.
  double next() const noexcept { return (a * g_b - b * g_a) / (g_b - g_a); }
  // x with g(x) = g replaces the end whose g has the same sign (a when g is 0); true when it replaced a.
  bool update(double x, double g) noexcept {
    if (g * g_b > 0.0) {
      b = x;
      g_b = g;
      if (side == -1) g_a *= 0.5;
      side = -1;
      return false;
    }
    a = x;
    g_a = g;
    if (side == 1) g_b *= 0.5;
    side = 1;
    return true;
  }
};

}  // namespace rail::contact
