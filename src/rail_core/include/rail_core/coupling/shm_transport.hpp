// Shared-memory transport (paper section 5.2, Figure 13): one region per direction under /dev/shm
// (shm_open + mmap), each carrying a header (shm_layout.hpp) and one frame. The turn flag in the header is
// the binary semaphore: the writer waits for its turn, writes the frame and gives the turn to the reader;
// the reader copies the frame out and gives the turn back. Waits spin for a bounded time, then yield the
// CPU for a bounded time, then sleep on a process-shared futex, always with a deadline.
//
// Each node creates the region it writes ("v2t" by the vehicle, "t2v" by the track; mode 0600) and
// attaches the one it reads, waiting for it up to the attach timeout. A region left by a crashed run
// (creator process gone, or closed flag set) is replaced by its creator and ignored by the attaching
// side. Both sides unlink both regions on close. Linux only.
#pragma once

#include <cstdint>
#include <string>

#include "rail_core/coupling/shm_layout.hpp"
#include "rail_core/coupling/transport.hpp"

namespace rail::core::coupling {

struct ShmOptions {
  Role role = Role::kVehicle;
  std::uint64_t scene_hash = 0;                  // Scene::hash; part of the region names and checked on attach
  int wheel_capacity = 0;                        // wheels per frame (Scene::wheel_count()), > 0
  std::string run_id;                            // same on both nodes, [A-Za-z0-9_.-], 1..48 chars: separates runs
  double attach_timeout = 30.0;                  // longest wait for the peer's region [s] (solver.handshake_timeout)
  std::string peer_host;                         // the peer's host name if the caller knows it; empty = unknown
  double spin_time = 100e-6;                     // busy-wait before yielding [s], 0: none
  double yield_time = 2e-3;                      // then sched_yield() up to this wait [s] before the futex
  const std::atomic<bool>* interrupt = nullptr;  // optional: ends any wait with kInterrupted
  std::string name_prefix = "railsim";           // [A-Za-z0-9_.-], first part of the region names
};

// Name of the region written by `writer`: "/<prefix>_<scene hash, 16 hex>_<run id>_v2t" (or "_t2v").
std::string shmRegionName(const std::string& prefix, std::uint64_t scene_hash, const std::string& run_id, Role writer);

// Whether a process is running: exists, is not a zombie and, when start_time != 0, started at that time
// (/proc/<pid>/stat field 22), which tells a reused pid apart.
bool shmProcessAlive(std::int64_t pid, std::uint64_t start_time);

// One mapped region (no protocol). Used by ShmTransport; public for tests and tools.
class ShmRegion {
 public:
  struct Spec {
    std::string name;  // "/..." as for shm_open
    shm::FrameKind kind = shm::FrameKind::kWheelStates;
    std::uint32_t wheel_capacity = 0;
    std::uint64_t scene_hash = 0;
  };
  // Create the region (mode 0600), replacing a stale one (creator gone, or closed). Throws CouplingError
  // (kRefused) when a live process owns the name, (kError) when a system call fails.
  static ShmRegion create(const Spec& spec);
  // Wait up to `deadline` for the region to exist with a complete header from a live creator, then check
  // layout version, frame kind, host, wheel capacity (payload size), region size and scene hash. Throws
  // CouplingError: kRefused naming the field and both values, kTimeout naming `peer` and the region.
  static ShmRegion attach(const Spec& spec, Deadline deadline, Role peer, double timeout_s,
                          const std::atomic<bool>* interrupt);

  ShmRegion() = default;
  ShmRegion(ShmRegion&& o) noexcept;
  ShmRegion& operator=(ShmRegion&& o) noexcept;
  ShmRegion(const ShmRegion&) = delete;
  ShmRegion& operator=(const ShmRegion&) = delete;
  ~ShmRegion();  // unmaps; does not unlink

  bool mapped() const { return base_ != nullptr; }
  const std::string& name() const { return name_; }
  shm::ShmHeader& header() const { return *reinterpret_cast<shm::ShmHeader*>(base_); }
  unsigned char* payload() const { return static_cast<unsigned char*>(base_) + shm::kShmPayloadOffset; }
  std::size_t size() const { return size_; }
  // Unlink the name if it still refers to this region (not to a newer one of the same name).
  void unlinkIfSame();
  void unmap();
  // After create(): what it replaced, "" when the name was free: "replaced the stale region <name> left
  // by pid P on host 'H' (its creator is gone)", "(closed by its writer)" or "(incomplete, left by a
  // creator that died while setting it up)". For the node's log.
  const std::string& replacedStale() const { return replaced_; }

 private:
  std::string name_;
  std::string replaced_;
  int fd_ = -1;
  void* base_ = nullptr;
  std::size_t size_ = 0;
};

class ShmTransport : public FrameTransport {
 public:
  // Creates this side's region and attaches the peer's (blocking up to options.attach_timeout). Throws
  // std::runtime_error for bad options, CouplingError for a refused or missing peer.
  explicit ShmTransport(const ShmOptions& options);
  ~ShmTransport() override;  // close()
  ShmTransport(const ShmTransport&) = delete;
  ShmTransport& operator=(const ShmTransport&) = delete;

  Role role() const override { return options_.role; }
  Result sendStates(const WheelStateFrame& frame, Deadline deadline) override;
  Result receiveWrenches(WrenchFrame& frame, Deadline deadline) override;
  Result receiveStates(WheelStateFrame& frame, Deadline deadline) override;
  Result sendWrenches(const WrenchFrame& frame, Deadline deadline) override;
  void close() override;

  const std::string& writeRegionName() const { return write_.name(); }
  const std::string& readRegionName() const { return read_.name(); }
  std::int64_t peerPid() const { return peer_pid_; }
  // This side's region replaced a stale one of a crashed run: ShmRegion::replacedStale(), else "".
  const std::string& replacedStale() const { return write_.replacedStale(); }

 private:
  // Wait until the region's turn flag equals `want_reader_turn`; the peer's closed bit ends the wait.
  Result waitTurn(ShmRegion& region, bool want_reader_turn, std::uint32_t peer_closed_bit, Deadline deadline);
  Result misuse(const char* call) const;
  // One frame out or in, the same for states and wrenches: the role and capacity checks, the turn, the stamp
  // and count, each record through `convert` (Record: the region's record type), the turn handed over.
  template <class Record, class Frame, class Convert>
  Result sendFrame(const Frame& frame, Role sender, const char* call, Deadline deadline, Convert convert);
  template <class Record, class Frame, class Convert>
  Result receiveFrame(Frame& frame, Role receiver, const char* call, Deadline deadline, Convert convert);

  ShmOptions options_;
  Clock::duration spin_budget_{};   // options_.spin_time
  Clock::duration yield_budget_{};  // options_.yield_time
  ShmRegion write_;                 // the region this side writes (and created)
  ShmRegion read_;                  // the peer's region
  std::int64_t peer_pid_ = 0;
  std::uint64_t peer_start_time_ = 0;
  bool closed_ = false;
};

}  // namespace rail::core::coupling
