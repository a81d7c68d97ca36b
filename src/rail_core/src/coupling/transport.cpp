#include "rail_core/coupling/transport.hpp"

#include <rail_contact/enum_words.hpp>

#include "rail_core/exit_codes.hpp"

namespace rail::core::coupling {

namespace {
constexpr contact::Word<Status> kStatusWords[] = {
    {"ok", Status::kOk},           {"timeout", Status::kTimeout},         {"peer closed", Status::kPeerClosed},
    {"refused", Status::kRefused}, {"interrupted", Status::kInterrupted}, {"error", Status::kError}};
static_assert(contact::namesEvery(kStatusWords, Status::kError));
}  // namespace

const char* toString(Role r) { return r == Role::kVehicle ? "vehicle" : "track"; }

const char* toString(Status s) { return contact::wordOf(kStatusWords, s); }

int exitCode(Status s) {
  switch (s) {
    case Status::kOk:
      return kExitOk;
    case Status::kTimeout:
    case Status::kPeerClosed:
      return kExitPeerTimeout;
    case Status::kRefused:
      return kExitPeerRefused;
    case Status::kInterrupted:
      return kExitInterrupted;
    case Status::kError:
      return kExitInternal;
  }
  return kExitInternal;
}

}  // namespace rail::core::coupling
