// Byte layout of one shared-memory region of the shm transport (paper section 5.2, Figure 13). One region
// per direction: "v2t" (wheel states, written by the vehicle) and "t2v" (wrenches, written by the track).
// Each region is a header followed, at kShmPayloadOffset, by one frame. Native byte order; both processes
// run on one host. The fields up to creator_start_time keep their offsets in every layout version so that
// a region of another version can still be recognised as stale or refused.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>

namespace rail::core::coupling::shm {

constexpr std::uint64_t kShmMagic = 0x314d48534c494152ull;  // "RAILSHM1" read as little-endian bytes
constexpr std::uint32_t kShmLayoutVersion = 1;
constexpr std::size_t kShmPayloadOffset = 256;  // header bytes reserved before the frame
constexpr std::size_t kShmHostNameSize = 64;

enum class FrameKind : std::uint32_t { kWheelStates = 1, kWrenches = 2 };

// Bits of ShmHeader::state, the one 32-bit futex word of a region. The turn flag, the two closed flags
// and the waiter flag share one word so that any change of them wakes a sleeping peer (no lost wake-up
// between "checked the closed flag" and "went to sleep").
constexpr std::uint32_t kTurnReader = 1u << 0;    // set: a frame waits for the reader; clear: writer's turn
constexpr std::uint32_t kWriterClosed = 1u << 1;  // the writer closed its end (clean shutdown)
constexpr std::uint32_t kReaderClosed = 1u << 2;  // the reader closed its end
constexpr std::uint32_t kWaiters = 1u << 3;       // someone may sleep on the word: wake on change

struct ShmHeader {
  std::atomic<std::uint64_t> magic;              // kShmMagic, stored last (release) once the header is complete
  std::uint32_t layout_version;                  // kShmLayoutVersion
  std::uint32_t header_size;                     // kShmPayloadOffset
  std::uint64_t payload_size;                    // bytes of the frame area (shmPayloadSize)
  std::uint32_t wheel_capacity;                  // wheels the frame area holds
  std::uint32_t frame_kind;                      // FrameKind
  std::uint64_t scene_hash;                      // hash of the resolved scene of the creating node
  std::int64_t creator_pid;                      // process that created (and writes) the region
  std::uint64_t creator_start_time;              // its start time, /proc/<pid>/stat field 22 [clock ticks]; 0 unknown
  char creator_host[kShmHostNameSize];           // gethostname() of the creator, NUL-terminated
  alignas(64) std::atomic<std::uint32_t> state;  // futex word: kTurnReader | kWriterClosed | ...
};
static_assert(sizeof(ShmHeader) <= kShmPayloadOffset, "header exceeds its reserved bytes");
static_assert(std::atomic<std::uint32_t>::is_always_lock_free, "futex word must be lock free");
static_assert(std::atomic<std::uint64_t>::is_always_lock_free, "magic must be lock free");
static_assert(sizeof(std::atomic<std::uint32_t>) == 4, "futex word must be 32 bits");

// Frame stamp at the start of the payload.
struct ShmFrameHead {
  std::uint64_t step;
  double time;  // [s]
  std::uint64_t scene_hash;
  std::uint32_t count;  // wheels in use
  std::uint32_t reserved;
};

// One wheel record of a wheel-states frame; quaternion stored x, y, z, w.
struct ShmWheelState {
  std::uint32_t id;
  std::uint32_t reserved;
  double arc_length;                  // [m]
  double p_wheel_in_world[3];         // [m]
  double q_wheelset_to_world[4];      // x, y, z, w
  double v_wheel_in_world[3];         // [m/s]
  double omega_wheelset_in_world[3];  // [rad/s]
};

// One wheel record of a wrench frame.
struct ShmWheelWrench {
  std::uint32_t id;
  std::uint32_t reserved;
  double f_wheel_in_world[3];  // [N]
  double n_wheel_in_world[3];  // [N m]
};

// Bytes of the frame area for a kind and capacity.
constexpr std::size_t shmPayloadSize(FrameKind kind, std::uint32_t wheel_capacity) {
  return sizeof(ShmFrameHead) + static_cast<std::size_t>(wheel_capacity) *
                                    (kind == FrameKind::kWheelStates ? sizeof(ShmWheelState) : sizeof(ShmWheelWrench));
}
// Bytes of the whole region.
constexpr std::size_t shmRegionSize(FrameKind kind, std::uint32_t wheel_capacity) {
  return kShmPayloadOffset + shmPayloadSize(kind, wheel_capacity);
}

}  // namespace rail::core::coupling::shm
