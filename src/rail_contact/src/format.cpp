#include "rail_contact/format.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>

namespace rail::contact {

std::string formatNumber(double v) {
  if (std::isnan(v)) return "nan";
  if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
  // The shortest round-trip digits in scientific form ("d.ddde+X"); %g's choice of notation on them, with
  // at least 6 significant digits as %g has, so the text is %g's wherever %g was exact.
  char buf[64];
  const auto sci = std::to_chars(buf, buf + sizeof(buf) - 1, v, std::chars_format::scientific);
  *sci.ptr = '\0';
  char* e = std::find(buf, sci.ptr, 'e');
  const int digits = static_cast<int>(std::count_if(buf, e, [](char c) { return c >= '0' && c <= '9'; }));
  const int exponent = std::atoi(e + 1);
  if (exponent < -4 || exponent >= std::max(6, digits)) return buf;
  const auto fixed = std::to_chars(buf, buf + sizeof(buf), v, std::chars_format::fixed);
  return std::string(buf, fixed.ptr);
}

}  // namespace rail::contact
