#include "rail_core/coupling/transport.hpp"

#include "rail_core/exit_codes.hpp"

namespace rail::core::coupling {

const char* toString(Role r) { return r == Role::kVehicle ? "vehicle" : "track"; }

const char* toString(Status s) {
  switch (s) {
    case Status::kOk:
      return "ok";
    case Status::kTimeout:
      return "timeout";
    case Status::kPeerClosed:
      return "peer closed";
    case Status::kRefused:
      return "refused";
    case Status::kInterrupted:
      return "interrupted";
    case Status::kError:
      return "error";
  }
  return "unknown";
}

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
