// The one number formatter for the project's messages (errors, refusals, summaries): a double as the
// shortest text that reads back to the same double, so a message never shows a rounded value.
#pragma once

#include <string>

namespace rail::contact {

/// Shortest round-trip text of v, in printf's %g notation (fixed for exponents -4 .. max(5, digits - 1),
/// scientific otherwise): 0.5 -> "0.5", 30 -> "30", 100000 -> "100000", 1e-5 -> "1e-05", 1.23456789 ->
/// "1.23456789", 0.1 + 0.2 -> "0.30000000000000004"; "nan", "inf", "-inf".
std::string formatNumber(double v);

}  // namespace rail::contact
