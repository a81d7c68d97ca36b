// The transport between the vehicle and track nodes: send and receive of both frame kinds, each with a
// deadline, and a clean close. ROS-free; the shared-memory transport (shm_transport.hpp), the in-process
// loopback (loopback_transport.hpp) and the ROS service/topic transports implement it.
#pragma once

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>

#include "rail_core/coupling/frames.hpp"

namespace rail::core::coupling {

using Clock = std::chrono::steady_clock;
using Deadline = Clock::time_point;

// Which node an endpoint belongs to. The vehicle writes wheel states and reads wrenches; the track the
// reverse.
enum class Role { kVehicle, kTrack };
const char* toString(Role r);  // "vehicle" / "track"
inline Role peerOf(Role r) { return r == Role::kVehicle ? Role::kTrack : Role::kVehicle; }

// Outcome of a transport call or a protocol exchange.
enum class Status {
  kOk,           // done
  kTimeout,      // the peer did not answer before the deadline
  kPeerClosed,   // the peer closed the connection (clean shutdown) or its process ended
  kRefused,      // a frame or region was refused (scene hash, step index, size, version, host)
  kInterrupted,  // the caller's interrupt flag was raised while waiting
  kError,        // a system call failed or the transport was misused (message says which)
};
const char* toString(Status s);

// The exit code (rail_core/exit_codes.hpp) a node returns after a failed exchange with this status:
// kTimeout and kPeerClosed -> kExitPeerTimeout (the peer stopped answering), kRefused -> kExitPeerRefused,
// kInterrupted -> kExitInterrupted, kError -> kExitInternal, kOk -> kExitOk.
int exitCode(Status s);

// Status plus, when not kOk, one message. The message is only built on failure (no allocation on the
// normal path: an empty std::string does not allocate).
struct Result {
  Status status = Status::kOk;
  std::string message;
  bool ok() const { return status == Status::kOk; }
  explicit operator bool() const { return ok(); }
};

// Thrown while setting a transport up (create/attach), carrying the status for the exit code.
class CouplingError : public std::runtime_error {
 public:
  CouplingError(Status status, const std::string& what) : std::runtime_error(what), status_(status) {}
  Status status() const { return status_; }

 private:
  Status status_;
};

// One endpoint of a transport. A frame is handed over whole or not at all; the transport only moves
// frames (stamps are checked by the protocol). Calls for the other role's direction return kError.
// Every call returns by its deadline; a deadline already past still lets data that is ready through.
class FrameTransport {
 public:
  virtual ~FrameTransport() = default;
  virtual Role role() const = 0;
  // Vehicle side: hand over the states (waits until the previous frame was taken), then read wrenches.
  virtual Result sendStates(const WheelStateFrame& frame, Deadline deadline) = 0;
  virtual Result receiveWrenches(WrenchFrame& frame, Deadline deadline) = 0;
  // Track side.
  virtual Result receiveStates(WheelStateFrame& frame, Deadline deadline) = 0;
  virtual Result sendWrenches(const WrenchFrame& frame, Deadline deadline) = 0;
  // Tell the peer this side is done and release the resources. Idempotent; never blocks.
  virtual void close() = 0;
};

}  // namespace rail::core::coupling
