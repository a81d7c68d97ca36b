// The shared-memory transport across two processes (the peer is fork()ed): bit-exact round trip, attach
// refusals, stale regions, timeouts, shutdown, permissions and cleanup of /dev/shm.
#include <gtest/gtest.h>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "rail_core/coupling/protocol.hpp"
#include "rail_core/coupling/shm_transport.hpp"

using namespace rail::core::coupling;

namespace {

constexpr std::uint64_t kHash = 0x5ca1ab1e00000001ull;
constexpr int kWheels = 8;

// Region names of these tests start with this prefix (unique to the test process).
std::string testPrefix() { return "railsimtest" + std::to_string(getpid()); }

std::vector<std::string> leftoverRegions() {
  std::vector<std::string> found;
  if (DIR* d = opendir("/dev/shm")) {
    while (dirent* e = readdir(d))
      if (std::string(e->d_name).rfind(testPrefix(), 0) == 0) found.push_back(e->d_name);
    closedir(d);
  }
  return found;
}

double secondsSince(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// splitmix64: deterministic 64-bit patterns.
std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
double fromBits(std::uint64_t b) {
  double d;
  std::memcpy(&d, &b, sizeof d);
  return d;
}
std::uint64_t bits(double d) {
  std::uint64_t b;
  std::memcpy(&b, &d, sizeof b);
  return b;
}
// Every double of the frames is an arbitrary bit pattern (NaNs with payloads, infinities, subnormals,
// negative zero included) so that only a bit-exact copy passes.
double pattern(std::uint64_t step, int wheel, int field) {
  const std::uint64_t seed = (step << 16) ^ (static_cast<std::uint64_t>(wheel) << 8) ^ field;
  switch (field) {  // a few fixed special values besides the random ones
    case 0:
      return wheel == 0 ? -0.0 : fromBits(mix(seed));
    case 1:
      return wheel == 1 ? fromBits(1) : fromBits(mix(seed));  // subnormal
    case 2:
      return wheel == 2 ? fromBits(0x7ff8000000001234ull + step) : fromBits(mix(seed));  // NaN
    default:
      return fromBits(mix(seed));
  }
}
void fillStates(WheelStateFrame& f, std::uint64_t step) {
  for (int i = 0; i < kWheels; ++i) {
    WheelState& w = f.wheels[i];
    w.id = static_cast<std::uint32_t>(mix(step * 31 + i));
    w.arc_length = pattern(step, i, 0);
    for (int j = 0; j < 3; ++j) w.p_wheel_in_world[j] = pattern(step, i, 1 + j);
    // A rotation (the wire carries it as a unit quaternion, so arbitrary bits would not survive).
    w.R_wheelset_to_world = Eigen::AngleAxisd(1e-3 * static_cast<double>(mix(step * 7 + i) % 6283),
                                              Eigen::Vector3d(1.0, 0.2 * i, -0.3).normalized())
                                .toRotationMatrix();
    for (int j = 0; j < 3; ++j) w.v_wheel_in_world[j] = pattern(step, i, 8 + j);
    for (int j = 0; j < 3; ++j) w.omega_wheelset_in_world[j] = pattern(step, i, 11 + j);
  }
}
void fillWrenches(WrenchFrame& f, std::uint64_t step) {
  for (int i = 0; i < kWheels; ++i) {
    WheelWrench& w = f.wheels[i];
    w.id = static_cast<std::uint32_t>(mix(step * 37 + i));
    for (int j = 0; j < 3; ++j) w.f_wheel_in_world[j] = pattern(step, i, 20 + j);
    for (int j = 0; j < 3; ++j) w.n_wheel_in_world[j] = pattern(step, i, 23 + j);
  }
}
template <class V>
bool sameBits(const V& a, const V& b) {
  for (int j = 0; j < a.size(); ++j)
    if (bits(a[j]) != bits(b[j])) return false;
  return true;
}
Eigen::Matrix<double, 9, 1> flat(const Eigen::Matrix3d& m) {
  return Eigen::Map<const Eigen::Matrix<double, 9, 1>>(m.data());
}
// a as received, b as sent: every field bit for bit; the orientation as the wire's quaternion form gives it
// back (frames.hpp).
bool sameBits(const WheelStateFrame& a, const WheelStateFrame& b) {
  if (a.count != b.count) return false;
  for (std::uint32_t i = 0; i < a.count; ++i) {
    const WheelState &x = a.wheels[i], &y = b.wheels[i];
    if (x.id != y.id || bits(x.arc_length) != bits(y.arc_length) || !sameBits(x.p_wheel_in_world, y.p_wheel_in_world) ||
        !sameBits(flat(x.R_wheelset_to_world), flat(orientationFromWire(wireOrientation(y.R_wheelset_to_world)))) ||
        !x.R_wheelset_to_world.isApprox(y.R_wheelset_to_world, 1e-14) ||
        !sameBits(x.v_wheel_in_world, y.v_wheel_in_world) ||
        !sameBits(x.omega_wheelset_in_world, y.omega_wheelset_in_world))
      return false;
  }
  return true;
}
bool sameBits(const WrenchFrame& a, const WrenchFrame& b) {
  if (a.count != b.count) return false;
  for (std::uint32_t i = 0; i < a.count; ++i) {
    const WheelWrench &x = a.wheels[i], &y = b.wheels[i];
    if (x.id != y.id || !sameBits(x.f_wheel_in_world, y.f_wheel_in_world) ||
        !sameBits(x.n_wheel_in_world, y.n_wheel_in_world))
      return false;
  }
  return true;
}

CouplingConfig config(double timeout = 10.0) {
  CouplingConfig c;
  c.track_step = 2e-5;
  c.exchange_timeout = timeout;
  c.scene_hash = kHash;
  c.wheel_count = kWheels;
  return c;
}

// Children of the running test: killed and reaped whatever happens.
class ShmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    static int counter = 0;
    run_id = "r" + std::to_string(++counter);
  }
  void TearDown() override {
    for (pid_t pid : children) {
      if (pid <= 0) continue;
      kill(pid, SIGKILL);
      waitpid(pid, nullptr, 0);
    }
    // Nothing may be left in /dev/shm by a passing test; remove what a failing one left.
    const auto left = leftoverRegions();
    EXPECT_TRUE(left.empty()) << left.size() << " region(s) left, first: " << left.front();
    for (const std::string& n : left) shm_unlink(("/" + n).c_str());
  }

  ShmOptions options(Role role, double attach_timeout = 10.0) const {
    ShmOptions o;
    o.role = role;
    o.scene_hash = kHash;
    o.wheel_capacity = kWheels;
    o.run_id = run_id;
    o.attach_timeout = attach_timeout;
    o.name_prefix = testPrefix();
    return o;
  }
  std::string name(Role writer) const { return shmRegionName(testPrefix(), kHash, run_id, writer); }
  bool exists(Role writer) const {
    struct stat st {};
    return stat(("/dev/shm" + name(writer)).c_str(), &st) == 0;
  }

  // Run body in a child process; its return value is the exit code (99 for an exception).
  pid_t spawn(const std::function<int()>& body) {
    const pid_t pid = fork();
    if (pid == 0) {
      int code = 98;
      try {
        code = body();
      } catch (...) {
        code = 99;
      }
      _exit(code);
    }
    children.push_back(pid);
    return pid;
  }
  // Exit code of a child, -1 if it did not end within `timeout` seconds (then it is killed).
  int waitChild(pid_t pid, double timeout = 20.0) {
    const auto t0 = Clock::now();
    for (;;) {
      int status = 0;
      if (waitpid(pid, &status, WNOHANG) == pid) {
        for (pid_t& c : children)
          if (c == pid) c = 0;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      if (secondsSince(t0) > timeout) return -1;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }
  void kill9(pid_t pid) {
    kill(pid, SIGKILL);
    waitpid(pid, nullptr, 0);
    for (pid_t& c : children)
      if (c == pid) c = 0;
  }
  // Waits until the writer's region is complete (its magic is stored last), not merely named: a process
  // killed between creating the name and finishing the header leaves an incomplete region, another case.
  bool waitComplete(Role writer, double timeout = 10.0) {
    const auto t0 = Clock::now();
    for (;;) {
      bool complete = false;
      const int fd = shm_open(name(writer).c_str(), O_RDONLY, 0);
      if (fd >= 0) {
        struct stat st {};
        if (fstat(fd, &st) == 0 && static_cast<std::size_t>(st.st_size) >= sizeof(shm::ShmHeader)) {
          void* p = mmap(nullptr, sizeof(shm::ShmHeader), PROT_READ, MAP_SHARED, fd, 0);
          if (p != MAP_FAILED) {
            complete = static_cast<const shm::ShmHeader*>(p)->magic.load(std::memory_order_acquire) == shm::kShmMagic;
            munmap(p, sizeof(shm::ShmHeader));
          }
        }
        close(fd);
      }
      if (complete) return true;
      if (secondsSince(t0) > timeout) return false;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }

  std::string run_id;
  std::vector<pid_t> children;
};

// A child track that answers `steps` steps with fillWrenches and checks the states it receives bit for
// bit (exit 0 if all matched, 10 + reason otherwise).
int echoTrack(const ShmOptions& o, int steps, bool close_at_end = true) {
  ShmTransport t(o);
  TrackCoupling track(config(), t);
  WheelStateFrame expected(kWheels);
  expected.count = kWheels;
  int mismatches = 0;
  for (int k = 0; k < steps; ++k) {
    if (!track.receive()) return 11;
    fillStates(expected, static_cast<std::uint64_t>(k));
    if (!sameBits(track.states(), expected)) ++mismatches;
    fillWrenches(track.wrenches(), static_cast<std::uint64_t>(k));
    if (!track.send()) return 12;
  }
  if (close_at_end) t.close();
  return mismatches == 0 ? 0 : 13;
}

}  // namespace

// Frames cross the process boundary bit for bit, in both directions, for 200 steps.
TEST_F(ShmTest, RoundTripAcrossProcessesIsBitExact) {
  const ShmOptions track_options = options(Role::kTrack);
  const pid_t child = spawn([&] { return echoTrack(track_options, 200); });
  ShmTransport t(options(Role::kVehicle));
  EXPECT_EQ(t.peerPid(), child);
  VehicleCoupling v(config(), t);
  WrenchFrame expected(kWheels);
  expected.count = kWheels;
  for (std::uint64_t k = 0; k < 200; ++k) {
    fillStates(v.states(), k);
    const Result r = v.exchange();
    ASSERT_TRUE(r) << r.message;
    fillWrenches(expected, k);
    ASSERT_EQ(v.lastWrenches().step, k);
    ASSERT_TRUE(sameBits(v.lastWrenches(), expected)) << "step " << k;
  }
  EXPECT_EQ(waitChild(child), 0);  // 0: the track saw every state frame bit for bit
  t.close();
  EXPECT_FALSE(exists(Role::kVehicle));
  EXPECT_FALSE(exists(Role::kTrack));
}

// Regions are created with mode 0600, even under a permissive umask.
TEST_F(ShmTest, RegionsArePrivateToTheUser) {
  const mode_t old_mask = umask(0);
  ShmRegion r = ShmRegion::create({name(Role::kVehicle), shm::FrameKind::kWheelStates, kWheels, kHash});
  umask(old_mask);
  struct stat st {};
  ASSERT_EQ(stat(("/dev/shm" + name(Role::kVehicle)).c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  EXPECT_EQ(st.st_uid, getuid());
  EXPECT_EQ(static_cast<std::size_t>(st.st_size), shm::shmRegionSize(shm::FrameKind::kWheelStates, kWheels));
  r.unlinkIfSame();
}

// Attach refuses a region whose payload size, total size, layout version or scene hash differ, naming the
// field and both values; the refusing side removes the region it had created.
TEST_F(ShmTest, AttachRefusesMismatchedRegions) {
  using shm::FrameKind;
  const std::string t2v = name(Role::kTrack);
  auto expect_refusal = [&](const std::string& message) {
    try {
      ShmTransport t(options(Role::kVehicle, 2.0));
      ADD_FAILURE() << "attached";
    } catch (const CouplingError& e) {
      EXPECT_EQ(e.status(), Status::kRefused);
      EXPECT_EQ(std::string(e.what()), message);
    }
    EXPECT_FALSE(exists(Role::kVehicle));  // its own region was removed
  };
  const std::size_t payload8 = shm::shmPayloadSize(FrameKind::kWrenches, 8);
  const std::size_t payload16 = shm::shmPayloadSize(FrameKind::kWrenches, 16);
  {  // wheel capacity 16 instead of 8
    ShmRegion r = ShmRegion::create({t2v, FrameKind::kWrenches, 16, kHash});
    expect_refusal("shm transport: region " + t2v + " refused: payload size " + std::to_string(payload8) +
                   " bytes (8 wheels) expected, " + std::to_string(payload16) + " bytes (16 wheels) in the region");
    r.unlinkIfSame();
  }
  {  // a region grown past its header's sizes
    ShmRegion r = ShmRegion::create({t2v, FrameKind::kWrenches, 8, kHash});
    const int fd = shm_open(t2v.c_str(), O_RDWR, 0);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(ftruncate(fd, static_cast<off_t>(r.size() + 4096)), 0);
    close(fd);
    expect_refusal("shm transport: region " + t2v + " refused: size " + std::to_string(r.size()) + " bytes expected, " +
                   std::to_string(r.size() + 4096) + " bytes in the region");
    r.unlinkIfSame();
  }
  {  // another layout version
    ShmRegion r = ShmRegion::create({t2v, FrameKind::kWrenches, 8, kHash});
    r.header().layout_version = 99;
    expect_refusal("shm transport: region " + t2v + " refused: layout version 1 expected, 99 in the region");
    r.unlinkIfSame();
  }
  {  // another scene under the same name
    ShmRegion r = ShmRegion::create({t2v, FrameKind::kWrenches, 8, 0x1111});
    expect_refusal("shm transport: region " + t2v +
                   " refused: scene hash 5ca1ab1e00000001 expected, 0000000000001111 in the region");
    r.unlinkIfSame();
  }
  {  // created on another host
    ShmRegion r = ShmRegion::create({t2v, FrameKind::kWrenches, 8, kHash});
    std::strcpy(r.header().creator_host, "elsewhere");
    char host[64] = {};
    gethostname(host, sizeof host - 1);
    expect_refusal("shm transport: region " + t2v + " refused: created on host 'elsewhere', this is host '" + host +
                   "'; the shm transport needs both nodes on one host (use transport service or topic)");
    r.unlinkIfSame();
  }
}

// A peer known to run on another host is refused before any region is made.
TEST_F(ShmTest, PeerOnAnotherHostIsRefused) {
  ShmOptions o = options(Role::kTrack);
  o.peer_host = "far-away.example.org";
  try {
    ShmTransport t(o);
    FAIL() << "accepted";
  } catch (const CouplingError& e) {
    EXPECT_EQ(e.status(), Status::kRefused);
    EXPECT_NE(std::string(e.what()).find("the vehicle runs on host 'far-away.example.org', this track on host '"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(exists(Role::kTrack));
  o.peer_host = "localhost";  // same host: accepted (then times out attaching, nobody is there)
  o.attach_timeout = 0.1;
  try {
    ShmTransport t(o);
  } catch (const CouplingError& e) {
    EXPECT_EQ(e.status(), Status::kTimeout) << e.what();
  }
}

// A region owned by a live process is not taken over; a closed one is replaced.
TEST_F(ShmTest, LiveRegionIsRefusedClosedOneReplaced) {
  const ShmRegion::Spec spec{name(Role::kVehicle), shm::FrameKind::kWheelStates, kWheels, kHash};
  ShmRegion first = ShmRegion::create(spec);
  try {
    ShmRegion::create(spec);
    FAIL() << "took over a live region";
  } catch (const CouplingError& e) {
    EXPECT_EQ(e.status(), Status::kRefused);
    EXPECT_EQ(
        std::string(e.what()).rfind(
            "shm transport: region " + spec.name + " is in use by pid " + std::to_string(getpid()) + " on host '", 0),
        0u)
        << e.what();
  }
  EXPECT_EQ(first.replacedStale(), "");  // the name was free
  first.header().state.fetch_or(shm::kWriterClosed);
  ShmRegion second = ShmRegion::create(spec);  // the closed one is stale: replaced
  EXPECT_EQ(second.header().state.load(), 0u);
  EXPECT_EQ(
      second.replacedStale().rfind(
          "replaced the stale region " + spec.name + " left by pid " + std::to_string(getpid()) + " on host '", 0),
      0u)
      << second.replacedStale();
  EXPECT_NE(second.replacedStale().find("' (closed by its writer)"), std::string::npos) << second.replacedStale();
  struct stat a {
  }, b{};
  ASSERT_EQ(stat(("/dev/shm" + spec.name).c_str(), &b), 0);
  second.unlinkIfSame();
  first.unlinkIfSame();  // no longer its name: does nothing
  EXPECT_NE(stat(("/dev/shm" + spec.name).c_str(), &a), 0);
}

// A creator killed between naming its region and completing the header leaves an empty region (before
// ftruncate) or a sized one without its magic: both are replaced after the grace for a creator still at
// work (1 s), and the message says why.
TEST_F(ShmTest, IncompleteRegionOfDeadCreatorIsReplaced) {
  const ShmRegion::Spec spec{name(Role::kVehicle), shm::FrameKind::kWheelStates, kWheels, kHash};
  for (const bool sized : {false, true}) {
    const int fd = shm_open(spec.name.c_str(), O_CREAT | O_EXCL | O_RDWR, 0600);
    ASSERT_GE(fd, 0);
    if (sized) ASSERT_EQ(ftruncate(fd, static_cast<off_t>(shm::shmRegionSize(spec.kind, spec.wheel_capacity))), 0);
    close(fd);
    const auto t0 = Clock::now();
    ShmRegion r = ShmRegion::create(spec);
    EXPECT_GE(secondsSince(t0), 0.9) << "replaced before the grace, sized " << sized;
    EXPECT_EQ(r.header().magic.load(), shm::kShmMagic);
    EXPECT_EQ(r.header().creator_pid, getpid());
    EXPECT_EQ(r.replacedStale(), "replaced the stale region " + spec.name +
                                     " (incomplete, left by a creator that died while setting it up)");
    r.unlinkIfSame();
  }
}

// A vehicle killed with SIGKILL leaves its region; the next run's track does not attach to it, and the
// next vehicle replaces it, after which the run works.
TEST_F(ShmTest, StaleRegionOfKilledProcessIsReplaced) {
  const ShmOptions vehicle_options = options(Role::kVehicle, 30.0);
  const pid_t doomed = spawn([&] {
    ShmTransport t(vehicle_options);  // creates v2t, then waits for a track that never comes
    return 20;
  });
  ASSERT_TRUE(waitComplete(Role::kVehicle));
  kill9(doomed);
  ASSERT_TRUE(exists(Role::kVehicle)) << "the killed process's region should still be there";
  {  // the stale region names a dead creator
    const int fd = shm_open(name(Role::kVehicle).c_str(), O_RDONLY, 0);
    ASSERT_GE(fd, 0);
    void* p = mmap(nullptr, sizeof(shm::ShmHeader), PROT_READ, MAP_SHARED, fd, 0);
    ASSERT_NE(p, MAP_FAILED);
    const auto* h = static_cast<const shm::ShmHeader*>(p);
    EXPECT_EQ(h->creator_pid, doomed);
    EXPECT_FALSE(shmProcessAlive(h->creator_pid, h->creator_start_time));
    munmap(p, sizeof(shm::ShmHeader));
    close(fd);
  }
  const ShmOptions track_options = options(Role::kTrack);
  const pid_t track = spawn([&] { return echoTrack(track_options, 3); });
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // the track now polls the stale region
  ShmTransport t(options(Role::kVehicle));
  EXPECT_EQ(t.peerPid(), track);
  EXPECT_EQ(t.replacedStale().rfind("replaced the stale region " + name(Role::kVehicle) + " left by pid " +
                                        std::to_string(doomed) + " on host '",
                                    0),
            0u)
      << t.replacedStale();
  EXPECT_NE(t.replacedStale().find("' (its creator is gone)"), std::string::npos) << t.replacedStale();
  VehicleCoupling v(config(), t);
  for (std::uint64_t k = 0; k < 3; ++k) {
    fillStates(v.states(), k);
    const Result r = v.exchange();
    ASSERT_TRUE(r) << r.message;
  }
  EXPECT_EQ(waitChild(track), 0);
  t.close();
}

// A track that never answers: the vehicle's exchange ends with kTimeout after the exchange timeout (slack
// 0.25 s: scheduling on a shared machine; the futex sleeps in slices of at most 50 ms), and a vehicle that
// never sends ends the track's wait the same way.
TEST_F(ShmTest, SilentPeerTimesOutWithinTheDeadline) {
  const ShmOptions track_options = options(Role::kTrack);
  const pid_t mute_track = spawn([&] {
    ShmTransport t(track_options);
    pause();  // never reads
    return 0;
  });
  {
    ShmTransport t(options(Role::kVehicle));
    VehicleCoupling v(config(0.3), t);
    const auto t0 = Clock::now();
    const Result r = v.exchange();
    const double elapsed = secondsSince(t0);
    EXPECT_EQ(r.status, Status::kTimeout);
    EXPECT_GE(elapsed, 0.3);
    EXPECT_LE(elapsed, 0.3 + 0.25);
    EXPECT_EQ(r.message,
              "vehicle: waiting for the contact wrenches of step 0: the track did not answer within 0.3 s "
              "(solver.exchange_timeout)");
  }
  kill9(mute_track);

  const ShmOptions vehicle_options = options(Role::kVehicle);
  const pid_t mute_vehicle = spawn([&] {
    ShmTransport t(vehicle_options);
    pause();  // never sends
    return 0;
  });
  {
    ShmTransport t(options(Role::kTrack));
    TrackCoupling track(config(0.3), t);
    const auto t0 = Clock::now();
    const Result r = track.receive();
    const double elapsed = secondsSince(t0);
    EXPECT_EQ(r.status, Status::kTimeout);
    EXPECT_GE(elapsed, 0.3);
    EXPECT_LE(elapsed, 0.3 + 0.25);
    EXPECT_EQ(r.message,
              "track: waiting for the wheel states of step 0: the vehicle did not answer within 0.3 s "
              "(solver.exchange_timeout)");
  }
  kill9(mute_vehicle);
}

// A track that answers two steps and closes: the vehicle's next exchange reports the closed peer at once.
TEST_F(ShmTest, ClosedPeerIsReported) {
  const ShmOptions track_options = options(Role::kTrack);
  const pid_t child = spawn([&] { return echoTrack(track_options, 2, true); });
  ShmTransport t(options(Role::kVehicle));
  VehicleCoupling v(config(10.0), t);
  for (std::uint64_t k = 0; k < 2; ++k) {
    fillStates(v.states(), k);
    ASSERT_TRUE(v.exchange());
  }
  const auto t0 = Clock::now();
  const Result r = v.exchange();
  EXPECT_EQ(r.status, Status::kPeerClosed);
  EXPECT_LE(secondsSince(t0), 2.0);  // the close wakes the waiter; far below the 10 s timeout
  EXPECT_EQ(r.message, "vehicle: waiting for the contact wrenches of step 2: the track closed the connection");
  EXPECT_EQ(waitChild(child), 0);
}

// A track killed mid-run (no close): the vehicle notices its process is gone within a few sleep slices
// instead of waiting for the whole exchange timeout.
TEST_F(ShmTest, KilledPeerIsReportedBeforeTheTimeout) {
  const ShmOptions track_options = options(Role::kTrack);
  const pid_t child = spawn([&] {
    ShmTransport t(track_options);
    TrackCoupling track(config(), t);
    if (!track.receive() || !track.send()) return 11;
    raise(SIGKILL);
    return 0;
  });
  ShmTransport t(options(Role::kVehicle));
  VehicleCoupling v(config(10.0), t);
  ASSERT_TRUE(v.exchange());
  const auto t0 = Clock::now();
  const Result r = v.exchange();
  EXPECT_EQ(r.status, Status::kPeerClosed);
  EXPECT_LE(secondsSince(t0), 1.0);  // 50 ms slices; 1 s leaves room for a loaded machine
  EXPECT_EQ(r.message,
            "vehicle: waiting for the contact wrenches of step 1: the track closed the connection "
            "(its process " +
                std::to_string(child) + " ended without closing)");
  EXPECT_EQ(waitChild(child), 128 + SIGKILL);
}

// Nobody to attach to: the constructor gives up after the attach timeout, naming the peer and the region.
TEST_F(ShmTest, MissingPeerTimesOutAttaching) {
  const auto t0 = Clock::now();
  try {
    ShmTransport t(options(Role::kTrack, 0.2));
    FAIL() << "attached to nobody";
  } catch (const CouplingError& e) {
    EXPECT_EQ(e.status(), Status::kTimeout);
    EXPECT_EQ(std::string(e.what()),
              "shm transport: the vehicle's region " + name(Role::kVehicle) + " did not appear within 0.2 s");
  }
  const double elapsed = secondsSince(t0);
  EXPECT_GE(elapsed, 0.2);
  EXPECT_LE(elapsed, 0.2 + 0.25);
  EXPECT_FALSE(exists(Role::kTrack));
}

TEST_F(ShmTest, BadOptionsAreRefused) {
  ShmOptions o = options(Role::kTrack);
  o.run_id = "a/b";
  try {
    ShmTransport t(o);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(), "shm transport: run id 'a/b' may only contain letters, digits, '_', '-' and '.'");
  }
  o = options(Role::kTrack);
  o.wheel_capacity = 0;
  EXPECT_THROW(ShmTransport t(o), std::runtime_error);
  for (const double bad : {-1e-6, 2.0}) {
    const std::string got = bad < 0.0 ? "-1e-06" : "2";
    o = options(Role::kTrack);
    o.spin_time = bad;
    try {
      ShmTransport t(o);
      FAIL() << "spin time " << bad << " accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "shm transport: spin time must be in [0, 1] s (got " + got + ")");
    }
    o = options(Role::kTrack);
    o.yield_time = bad;
    try {
      ShmTransport t(o);
      FAIL() << "yield time " << bad << " accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_EQ(std::string(e.what()), "shm transport: yield time must be in [0, 1] s (got " + got + ")");
    }
  }
}

// After all of the above, nothing of this test program is left in /dev/shm.
TEST(ShmCleanup, NothingLeftInDevShm) {
  const auto left = leftoverRegions();
  EXPECT_TRUE(left.empty()) << left.size() << " region(s) left, first: " << left.front();
}
