#include "rail_core/coupling/shm_transport.hpp"

#include <fcntl.h>
#include <linux/futex.h>
#include <sched.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstring>
#include <new>
#include <thread>

#include <rail_contact/format.hpp>

namespace rail::core::coupling {

using namespace shm;
using contact::formatNumber;

namespace {

// Longest futex sleep between checks of the peer's process, the interrupt flag and the deadline.
constexpr auto kSleepSlice = std::chrono::milliseconds(50);
// Poll period while waiting for the peer's region to appear.
constexpr auto kAttachPoll = std::chrono::milliseconds(5);
// How long a region without a complete header may stay so before its creator is taken for dead.
constexpr auto kIncompleteHeaderGrace = std::chrono::milliseconds(1000);

std::string hex(std::uint64_t v) {
  char buf[24];
  std::snprintf(buf, sizeof(buf), "%016llx", static_cast<unsigned long long>(v));
  return buf;
}
std::string sysError(const std::string& what) { return what + ": " + std::strerror(errno); }

const char* kindName(std::uint32_t k) {
  switch (static_cast<FrameKind>(k)) {
    case FrameKind::kWheelStates:
      return "wheel states";
    case FrameKind::kWrenches:
      return "wrenches";
  }
  return "unknown";
}

std::string thisHost() {
  char buf[kShmHostNameSize] = {};
  if (gethostname(buf, sizeof(buf) - 1) != 0) return {};
  return buf;
}

bool sameHost(const std::string& a, const std::string& b) {
  if (a == b) return true;
  auto is_local = [](const std::string& h) { return h == "localhost" || h == "127.0.0.1" || h == "::1"; };
  if (is_local(a) || is_local(b)) return true;
  auto short_name = [](const std::string& h) { return h.substr(0, h.find('.')); };
  return short_name(a) == short_name(b);
}

// /proc/<pid>/stat: state (field 3) and start time (field 22); false if unreadable. No allocation.
bool readProcStat(std::int64_t pid, char& state, std::uint64_t& start_time) {
  char path[48];
  std::snprintf(path, sizeof(path), "/proc/%lld/stat", static_cast<long long>(pid));
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  char buf[1024];
  const ssize_t n = ::read(fd, buf, sizeof(buf) - 1);
  ::close(fd);
  if (n <= 0) return false;
  buf[n] = '\0';
  const char* p = std::strrchr(buf, ')');  // the command name may hold spaces and parentheses
  if (!p) return false;
  ++p;
  for (int field = 3; field <= 22; ++field) {
    while (*p == ' ') ++p;
    if (*p == '\0') return false;
    if (field == 3) state = *p;
    if (field == 22) {
      start_time = std::strtoull(p, nullptr, 10);
      return true;
    }
    while (*p != ' ' && *p != '\0') ++p;
  }
  return false;
}

std::uint64_t ownStartTime() {
  char state = 0;
  std::uint64_t start = 0;
  return readProcStat(getpid(), state, start) ? start : 0;
}

void checkNamePart(const std::string& value, const char* field, std::size_t max_len) {
  if (value.empty() || value.size() > max_len)
    throw std::runtime_error("shm transport: " + std::string(field) + " '" + value + "' must have 1 to " +
                             std::to_string(max_len) + " characters");
  for (char c : value)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'))
      throw std::runtime_error("shm transport: " + std::string(field) + " '" + value +
                               "' may only contain letters, digits, '_', '-' and '.'");
}

int futexWait(std::atomic<std::uint32_t>& word, std::uint32_t expected, Clock::duration timeout) {
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count();
  timespec ts{static_cast<time_t>(ns / 1000000000), static_cast<long>(ns % 1000000000)};
  return static_cast<int>(
      syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAIT, expected, &ts, nullptr, 0));
}
void futexWakeAll(std::atomic<std::uint32_t>& word) {
  syscall(SYS_futex, reinterpret_cast<std::uint32_t*>(&word), FUTEX_WAKE, INT_MAX, nullptr, nullptr, 0);
}

inline void cpuRelax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield");
#endif
}

// Set `set` and clear `clear` in the state word; wake sleepers if any were announced.
void changeState(std::atomic<std::uint32_t>& word, std::uint32_t set, std::uint32_t clear) {
  std::uint32_t old = word.load(std::memory_order_relaxed);
  while (!word.compare_exchange_weak(old, (old | set) & ~(clear | kWaiters), std::memory_order_acq_rel,
                                     std::memory_order_relaxed)) {
  }
  if (old & kWaiters) futexWakeAll(word);
}

// Liveness of a region's creator as recorded in its header.
bool creatorAlive(const ShmHeader& h) { return shmProcessAlive(h.creator_pid, h.creator_start_time); }

}  // namespace

std::string shmRegionName(const std::string& prefix, std::uint64_t scene_hash, const std::string& run_id, Role writer) {
  return "/" + prefix + "_" + hex(scene_hash) + "_" + run_id + (writer == Role::kVehicle ? "_v2t" : "_t2v");
}

bool shmProcessAlive(std::int64_t pid, std::uint64_t start_time) {
  if (pid <= 0 || pid > INT_MAX) return false;
  if (kill(static_cast<pid_t>(pid), 0) != 0 && errno != EPERM) return false;
  char state = 0;
  std::uint64_t start = 0;
  if (!readProcStat(pid, state, start)) return true;  // exists; /proc not readable: trust kill()
  if (state == 'Z' || state == 'X') return false;     // ended, not yet reaped
  return start_time == 0 || start == start_time;
}

// --- ShmRegion ------------------------------------------------------------------------------------------

ShmRegion::ShmRegion(ShmRegion&& o) noexcept
    : name_(std::move(o.name_)), replaced_(std::move(o.replaced_)), fd_(o.fd_), base_(o.base_), size_(o.size_) {
  o.fd_ = -1;
  o.base_ = nullptr;
  o.size_ = 0;
}

ShmRegion& ShmRegion::operator=(ShmRegion&& o) noexcept {
  if (this != &o) {
    unmap();
    name_ = std::move(o.name_);
    replaced_ = std::move(o.replaced_);
    fd_ = o.fd_;
    base_ = o.base_;
    size_ = o.size_;
    o.fd_ = -1;
    o.base_ = nullptr;
    o.size_ = 0;
  }
  return *this;
}

ShmRegion::~ShmRegion() { unmap(); }

void ShmRegion::unmap() {
  if (base_) munmap(base_, size_);
  if (fd_ >= 0) ::close(fd_);
  base_ = nullptr;
  fd_ = -1;
  size_ = 0;
}

void ShmRegion::unlinkIfSame() {
  if (fd_ < 0 || name_.empty()) return;
  struct stat mine {};
  if (fstat(fd_, &mine) != 0) return;
  const int other = shm_open(name_.c_str(), O_RDONLY, 0);
  if (other < 0) return;  // already unlinked
  struct stat theirs {};
  const bool same = fstat(other, &theirs) == 0 && theirs.st_dev == mine.st_dev && theirs.st_ino == mine.st_ino;
  ::close(other);
  if (same) shm_unlink(name_.c_str());
}

ShmRegion ShmRegion::create(const Spec& spec) {
  const std::size_t size = shmRegionSize(spec.kind, spec.wheel_capacity);
  std::string replaced;  // what was replaced on an earlier attempt
  for (int attempt = 0;; ++attempt) {
    const int fd = shm_open(spec.name.c_str(), O_CREAT | O_EXCL | O_RDWR, 0600);
    if (fd >= 0) {
      ShmRegion r;
      r.name_ = spec.name;
      r.fd_ = fd;
      // Exactly 0600 whatever the umask: the region is private to the user.
      if (fchmod(fd, S_IRUSR | S_IWUSR) != 0 || ftruncate(fd, static_cast<off_t>(size)) != 0) {
        const std::string msg = sysError("shm transport: setting up region " + spec.name);
        shm_unlink(spec.name.c_str());
        throw CouplingError(Status::kError, msg);
      }
      void* base = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
      if (base == MAP_FAILED) {
        const std::string msg = sysError("shm transport: mapping region " + spec.name);
        shm_unlink(spec.name.c_str());
        throw CouplingError(Status::kError, msg);
      }
      r.base_ = base;
      r.size_ = size;
      // ftruncate zero-fills: the state word starts at 0 = writer's turn, nobody closed.
      ShmHeader* h = new (base) ShmHeader;
      h->layout_version = kShmLayoutVersion;
      h->header_size = static_cast<std::uint32_t>(kShmPayloadOffset);
      h->payload_size = shmPayloadSize(spec.kind, spec.wheel_capacity);
      h->wheel_capacity = spec.wheel_capacity;
      h->frame_kind = static_cast<std::uint32_t>(spec.kind);
      h->scene_hash = spec.scene_hash;
      h->creator_pid = getpid();
      h->creator_start_time = ownStartTime();
      const std::string host = thisHost();
      std::strncpy(h->creator_host, host.c_str(), kShmHostNameSize - 1);
      h->state.store(0, std::memory_order_relaxed);
      h->magic.store(kShmMagic, std::memory_order_release);
      r.replaced_ = replaced;
      return r;
    }
    if (errno != EEXIST || attempt >= 20)
      throw CouplingError(Status::kError, sysError("shm transport: creating region " + spec.name));

    // The name exists: replace it if stale, refuse it if a live process owns it.
    const int old = shm_open(spec.name.c_str(), O_RDONLY, 0);
    if (old < 0 && errno == EACCES)
      throw CouplingError(Status::kRefused, "shm transport: region " + spec.name +
                                                " exists and belongs to another user (choose another run id)");
    if (old < 0) continue;  // unlinked meanwhile: try again
    struct stat st {};
    bool stale = false;
    std::string owner, why = "(incomplete, left by a creator that died while setting it up)";
    if (fstat(old, &st) == 0 && static_cast<std::size_t>(st.st_size) >= sizeof(ShmHeader)) {
      void* p = mmap(nullptr, sizeof(ShmHeader), PROT_READ, MAP_SHARED, old, 0);
      if (p != MAP_FAILED) {
        const auto* h = static_cast<const ShmHeader*>(p);
        if (h->magic.load(std::memory_order_acquire) != kShmMagic) {
          // Incomplete header: a creator in progress, or one that died while creating. Wait a little.
          std::this_thread::sleep_for(kIncompleteHeaderGrace);
          stale = h->magic.load(std::memory_order_acquire) != kShmMagic;
        } else {
          const bool alive = creatorAlive(*h);
          stale = !alive || (h->state.load(std::memory_order_acquire) & kWriterClosed);
          owner = "pid " + std::to_string(h->creator_pid) + " on host '" +
                  std::string(h->creator_host, strnlen(h->creator_host, kShmHostNameSize)) + "'";
          why = "left by " + owner + (alive ? " (closed by its writer)" : " (its creator is gone)");
        }
        munmap(p, sizeof(ShmHeader));
      }
    } else {
      std::this_thread::sleep_for(kIncompleteHeaderGrace);  // being sized by its creator, or left empty
      stale = fstat(old, &st) == 0 && static_cast<std::size_t>(st.st_size) < sizeof(ShmHeader);
    }
    ::close(old);
    if (!stale)
      throw CouplingError(Status::kRefused, "shm transport: region " + spec.name + " is in use by " +
                                                (owner.empty() ? std::string("another process") : owner) +
                                                " (another run with the same scene and run id?)");
    shm_unlink(spec.name.c_str());  // stale: replace it
    replaced = "replaced the stale region " + spec.name + " " + why;
  }
}

ShmRegion ShmRegion::attach(const Spec& spec, Deadline deadline, Role peer, double timeout_s,
                            const std::atomic<bool>* interrupt) {
  const std::size_t expected_size = shmRegionSize(spec.kind, spec.wheel_capacity);
  const std::string host = thisHost();
  std::string last_seen;  // why the last region found was not taken, for the timeout message
  auto refuse = [&](const std::string& field, const std::string& here, const std::string& there) {
    return CouplingError(Status::kRefused, "shm transport: region " + spec.name + " refused: " + field + " " + here +
                                               " expected, " + there + " in the region");
  };
  for (;;) {
    const int fd = shm_open(spec.name.c_str(), O_RDWR, 0);
    if (fd >= 0) {
      struct stat st {};
      if (fstat(fd, &st) == 0 && static_cast<std::size_t>(st.st_size) >= sizeof(ShmHeader)) {
        const std::size_t size = static_cast<std::size_t>(st.st_size);
        void* base = mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
        if (base == MAP_FAILED) {
          const std::string msg = sysError("shm transport: mapping region " + spec.name);
          ::close(fd);
          throw CouplingError(Status::kError, msg);
        }
        ShmRegion r;
        r.name_ = spec.name;
        r.fd_ = fd;
        r.base_ = base;
        r.size_ = size;
        const ShmHeader& h = r.header();
        const std::uint64_t magic = h.magic.load(std::memory_order_acquire);
        if (magic == kShmMagic) {
          if (!creatorAlive(h) || (h.state.load(std::memory_order_acquire) & kWriterClosed)) {
            last_seen = "only a stale region left by pid " + std::to_string(h.creator_pid) + " was found";
          } else {
            if (h.layout_version != kShmLayoutVersion)
              throw refuse("layout version", std::to_string(kShmLayoutVersion), std::to_string(h.layout_version));
            if (h.frame_kind != static_cast<std::uint32_t>(spec.kind))
              throw refuse("frame kind", kindName(static_cast<std::uint32_t>(spec.kind)), kindName(h.frame_kind));
            const std::string their_host(h.creator_host, strnlen(h.creator_host, kShmHostNameSize));
            if (!sameHost(host, their_host))
              throw CouplingError(Status::kRefused,
                                  "shm transport: region " + spec.name + " refused: created on host '" + their_host +
                                      "', this is host '" + host +
                                      "'; the shm transport needs both nodes on one host (use transport "
                                      "service or topic)");
            if (h.header_size != kShmPayloadOffset)
              throw refuse("header size", std::to_string(kShmPayloadOffset), std::to_string(h.header_size));
            if (h.wheel_capacity != spec.wheel_capacity ||
                h.payload_size != shmPayloadSize(spec.kind, spec.wheel_capacity))
              throw refuse("payload size",
                           std::to_string(shmPayloadSize(spec.kind, spec.wheel_capacity)) + " bytes (" +
                               std::to_string(spec.wheel_capacity) + " wheels)",
                           std::to_string(h.payload_size) + " bytes (" + std::to_string(h.wheel_capacity) + " wheels)");
            if (size != expected_size)
              throw refuse("size", std::to_string(expected_size) + " bytes", std::to_string(size) + " bytes");
            if (h.scene_hash != spec.scene_hash) throw refuse("scene hash", hex(spec.scene_hash), hex(h.scene_hash));
            return r;
          }
        } else if (magic != 0) {
          throw refuse("magic", hex(kShmMagic), hex(magic) + " (not a railsim region)");
        }
      } else {
        ::close(fd);
      }
    }
    if (interrupt && interrupt->load(std::memory_order_relaxed))
      throw CouplingError(Status::kInterrupted, "shm transport: interrupted while waiting for the " +
                                                    std::string(toString(peer)) + "'s region " + spec.name);
    if (Clock::now() >= deadline)
      throw CouplingError(Status::kTimeout, "shm transport: the " + std::string(toString(peer)) + "'s region " +
                                                spec.name + " did not appear within " + formatNumber(timeout_s) + " s" +
                                                (last_seen.empty() ? "" : " (" + last_seen + ")"));
    std::this_thread::sleep_for(kAttachPoll);
  }
}

// --- ShmTransport ---------------------------------------------------------------------------------------

ShmTransport::ShmTransport(const ShmOptions& options) : options_(options) {
  const char* self = toString(options.role);
  if (options.wheel_capacity <= 0)
    throw std::runtime_error("shm transport: wheel capacity must be > 0 (got " +
                             std::to_string(options.wheel_capacity) + ")");
  if (!(options.attach_timeout >= 0.0))
    throw std::runtime_error("shm transport: attach timeout must be >= 0 s (got " +
                             formatNumber(options.attach_timeout) + ")");
  if (!(options.spin_time >= 0.0 && options.spin_time <= 1.0))
    throw std::runtime_error("shm transport: spin time must be in [0, 1] s (got " + formatNumber(options.spin_time) +
                             ")");
  if (!(options.yield_time >= 0.0 && options.yield_time <= 1.0))
    throw std::runtime_error("shm transport: yield time must be in [0, 1] s (got " + formatNumber(options.yield_time) +
                             ")");
  spin_budget_ = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.spin_time));
  yield_budget_ = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.yield_time));
  checkNamePart(options.run_id, "run id", 48);
  checkNamePart(options.name_prefix, "name prefix", 32);
  const std::string host = thisHost();
  if (!options.peer_host.empty() && !sameHost(host, options.peer_host))
    throw CouplingError(Status::kRefused, std::string("shm transport: the ") + toString(peerOf(options.role)) +
                                              " runs on host '" + options.peer_host + "', this " + self + " on host '" +
                                              host +
                                              "'; the shm transport needs both nodes on one host (use transport "
                                              "service or topic)");

  const auto cap = static_cast<std::uint32_t>(options.wheel_capacity);
  const bool vehicle = options.role == Role::kVehicle;
  ShmRegion::Spec mine{shmRegionName(options.name_prefix, options.scene_hash, options.run_id, options.role),
                       vehicle ? FrameKind::kWheelStates : FrameKind::kWrenches, cap, options.scene_hash};
  ShmRegion::Spec theirs{shmRegionName(options.name_prefix, options.scene_hash, options.run_id, peerOf(options.role)),
                         vehicle ? FrameKind::kWrenches : FrameKind::kWheelStates, cap, options.scene_hash};
  const Deadline deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(options.attach_timeout));
  write_ = ShmRegion::create(mine);
  try {
    read_ = ShmRegion::attach(theirs, deadline, peerOf(options.role), options.attach_timeout, options.interrupt);
  } catch (...) {
    write_.header().state.fetch_or(kWriterClosed);
    write_.unlinkIfSame();
    write_.unmap();
    throw;
  }
  peer_pid_ = read_.header().creator_pid;
  peer_start_time_ = read_.header().creator_start_time;
}

ShmTransport::~ShmTransport() { close(); }

void ShmTransport::close() {
  if (closed_) return;
  closed_ = true;
  if (write_.mapped()) {
    write_.header().state.fetch_or(kWriterClosed, std::memory_order_acq_rel);
    futexWakeAll(write_.header().state);
    write_.unlinkIfSame();
    write_.unmap();
  }
  if (read_.mapped()) {
    read_.header().state.fetch_or(kReaderClosed, std::memory_order_acq_rel);
    futexWakeAll(read_.header().state);
    read_.unlinkIfSame();
    read_.unmap();
  }
}

Result ShmTransport::misuse(const char* call) const {
  if (closed_) return {Status::kError, std::string(call) + ": the transport is closed"};
  return {Status::kError, std::string(call) + " called on the " + toString(options_.role) + " end"};
}

Result ShmTransport::waitTurn(ShmRegion& region, bool want_reader_turn, std::uint32_t peer_closed_bit,
                              Deadline deadline) {
  std::atomic<std::uint32_t>& word = region.header().state;
  auto ready = [&](std::uint32_t s) { return ((s & kTurnReader) != 0) == want_reader_turn; };
  // Spins for spin_time of wall, not a count of pauses: a pause lasts 10 to 140 cycles by CPU, and a
  // spin that ends before the peer's step does costs a futex wake-up (tens of us on a virtual machine).
  const auto wait0 = Clock::now();
  bool peer_closed = false;
  if (spin_budget_.count() > 0) {
    const auto spin_end = wait0 + spin_budget_;
    for (unsigned i = 1;; ++i) {
      const std::uint32_t s = word.load(std::memory_order_acquire);
      if (ready(s)) return {};
      if (s & peer_closed_bit) {
        peer_closed = true;
        break;
      }
      cpuRelax();
      if (i % 64 == 0 && Clock::now() >= spin_end) break;
    }
  }
  // Then yields: a peer step of a few ms (the flexible track's) is met without a wake-up, and a CPU
  // another process needs is given up at once.
  if (!peer_closed && yield_budget_.count() > 0) {
    const auto yield_end = std::min(wait0 + yield_budget_, deadline);
    do {
      const std::uint32_t s = word.load(std::memory_order_acquire);
      if (ready(s)) return {};
      if (s & peer_closed_bit) break;
      sched_yield();
    } while (Clock::now() < yield_end);
  }
  bool slept_a_slice = false;  // the peer's process is only looked at after a whole slice of waiting
  for (;;) {
    std::uint32_t s = word.load(std::memory_order_acquire);
    if (ready(s)) return {};
    if (s & peer_closed_bit) return {Status::kPeerClosed, {}};
    if (options_.interrupt && options_.interrupt->load(std::memory_order_relaxed)) return {Status::kInterrupted, {}};
    const auto now = Clock::now();
    if (now >= deadline) return {Status::kTimeout, {}};
    if (slept_a_slice && !shmProcessAlive(peer_pid_, peer_start_time_))
      return {Status::kPeerClosed, "its process " + std::to_string(peer_pid_) + " ended without closing"};
    if (!(s & kWaiters)) {
      if (!word.compare_exchange_weak(s, s | kWaiters, std::memory_order_acq_rel, std::memory_order_acquire)) continue;
      s |= kWaiters;
    }
    // Sleeps only while the word still equals s: any turn or closed change in between returns at once.
    const auto slice = std::min<Clock::duration>(deadline - now, kSleepSlice);
    if (futexWait(word, s, slice) != 0 && errno == ETIMEDOUT) slept_a_slice = true;
  }
}

namespace {
void writeStamp(unsigned char* payload, const FrameStamp& stamp, std::uint32_t count) {
  ShmFrameHead head{stamp.step, stamp.time, stamp.scene_hash, count, 0};
  std::memcpy(payload, &head, sizeof(head));
}
std::uint32_t readStamp(const unsigned char* payload, FrameStamp& stamp) {
  ShmFrameHead head;
  std::memcpy(&head, payload, sizeof(head));
  stamp.step = head.step;
  stamp.time = head.time;
  stamp.scene_hash = head.scene_hash;
  return head.count;
}
template <class Vec>
void put(double* dst, const Vec& v) {
  for (int i = 0; i < v.size(); ++i) dst[i] = v[i];
}
template <class Vec>
void get(const double* src, Vec& v) {
  for (int i = 0; i < v.size(); ++i) v[i] = src[i];
}
Result tooMany(std::uint32_t count, std::uint32_t capacity, const char* where) {
  return {Status::kError, "frame of " + std::to_string(count) + " wheels exceeds the " + where + " capacity " +
                              std::to_string(capacity)};
}
}  // namespace

template <class Record, class Frame, class Convert>
Result ShmTransport::sendFrame(const Frame& frame, Role sender, const char* call, Deadline deadline, Convert convert) {
  if (closed_ || options_.role != sender) return misuse(call);
  const std::uint32_t cap = write_.header().wheel_capacity;
  if (frame.count > cap || frame.count > static_cast<std::uint32_t>(frame.capacity()))
    return tooMany(frame.count, cap, "region's");
  Result r = waitTurn(write_, false, kReaderClosed, deadline);
  if (!r) return r;
  unsigned char* p = write_.payload();
  writeStamp(p, frame, frame.count);
  auto* rec = reinterpret_cast<Record*>(p + sizeof(ShmFrameHead));
  for (std::uint32_t i = 0; i < frame.count; ++i) convert(frame.wheels[i], rec[i]);
  changeState(write_.header().state, kTurnReader, 0);
  return {};
}

template <class Record, class Frame, class Convert>
Result ShmTransport::receiveFrame(Frame& frame, Role receiver, const char* call, Deadline deadline, Convert convert) {
  if (closed_ || options_.role != receiver) return misuse(call);
  Result r = waitTurn(read_, true, kWriterClosed, deadline);
  if (!r) return r;
  const unsigned char* p = read_.payload();
  FrameStamp stamp;
  const std::uint32_t count = readStamp(p, stamp);
  if (count > read_.header().wheel_capacity || count > static_cast<std::uint32_t>(frame.capacity()))
    return tooMany(count, static_cast<std::uint32_t>(frame.capacity()), "receiving");
  static_cast<FrameStamp&>(frame) = stamp;
  frame.count = count;
  const auto* rec = reinterpret_cast<const Record*>(p + sizeof(ShmFrameHead));
  for (std::uint32_t i = 0; i < count; ++i) convert(rec[i], frame.wheels[i]);
  changeState(read_.header().state, 0, kTurnReader);
  return {};
}

Result ShmTransport::sendStates(const WheelStateFrame& frame, Deadline deadline) {
  return sendFrame<ShmWheelState>(frame, Role::kVehicle, "send_states", deadline,
                                  [](const WheelState& w, ShmWheelState& o) {
                                    o.id = w.id;
                                    o.reserved = 0;
                                    o.arc_length = w.arc_length;
                                    put(o.p_wheel_in_world, w.p_wheel_in_world);
                                    put(o.q_wheelset_to_world, wireOrientation(w.R_wheelset_to_world).coeffs());
                                    put(o.v_wheel_in_world, w.v_wheel_in_world);
                                    put(o.omega_wheelset_in_world, w.omega_wheelset_in_world);
                                  });
}

Result ShmTransport::receiveStates(WheelStateFrame& frame, Deadline deadline) {
  return receiveFrame<ShmWheelState>(frame, Role::kTrack, "receive_states", deadline,
                                     [](const ShmWheelState& o, WheelState& w) {
                                       w.id = o.id;
                                       w.arc_length = o.arc_length;
                                       get(o.p_wheel_in_world, w.p_wheel_in_world);
                                       Eigen::Quaterniond q;
                                       get(o.q_wheelset_to_world, q.coeffs());  // x, y, z, w
                                       w.R_wheelset_to_world = orientationFromWire(q);
                                       get(o.v_wheel_in_world, w.v_wheel_in_world);
                                       get(o.omega_wheelset_in_world, w.omega_wheelset_in_world);
                                     });
}

Result ShmTransport::sendWrenches(const WrenchFrame& frame, Deadline deadline) {
  return sendFrame<ShmWheelWrench>(frame, Role::kTrack, "send_wrenches", deadline,
                                   [](const WheelWrench& w, ShmWheelWrench& o) {
                                     o.id = w.id;
                                     o.reserved = 0;
                                     put(o.f_wheel_in_world, w.f_wheel_in_world);
                                     put(o.n_wheel_in_world, w.n_wheel_in_world);
                                   });
}

Result ShmTransport::receiveWrenches(WrenchFrame& frame, Deadline deadline) {
  return receiveFrame<ShmWheelWrench>(frame, Role::kVehicle, "receive_wrenches", deadline,
                                      [](const ShmWheelWrench& o, WheelWrench& w) {
                                        w.id = o.id;
                                        get(o.f_wheel_in_world, w.f_wheel_in_world);
                                        get(o.n_wheel_in_world, w.n_wheel_in_world);
                                      });
}

}  // namespace rail::core::coupling
