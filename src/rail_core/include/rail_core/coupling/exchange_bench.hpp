// The two ends of the exchange benchmarks (railsim_bench_shm, railsim_bench_transports): a vehicle end
// that times round trips of one exchange of 8 wheel states and 8 wrenches, a track end that answers each
// with wrenches made from the states, and the printed figures. For benchmark programs, not the nodes.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <vector>

#include <Eigen/Core>

#include "rail_core/coupling/protocol.hpp"

namespace rail::core::coupling::bench {

constexpr int kWheels = 8;
constexpr double kTrackStep = 2e-5;  // [s]

inline CouplingConfig config(std::uint64_t scene_hash) {
  CouplingConfig c;
  c.track_step = kTrackStep;
  c.exchange_timeout = 10.0;
  c.scene_hash = scene_hash;
  c.wheel_count = kWheels;
  return c;
}

// Track end: answers up to `steps` exchanges (or until the vehicle closes). 0 when all went well, 1 when a
// receive failed, 2 when a send failed.
inline int answerExchanges(FrameTransport& t, const CouplingConfig& config, long steps) {
  TrackCoupling track(config, t);
  for (long k = 0; k < steps; ++k) {
    const Result r = track.receive();
    if (r.status == Status::kPeerClosed) return 0;
    if (!r) {
      std::fprintf(stderr, "%s\n", r.message.c_str());
      return 1;
    }
    for (int i = 0; i < kWheels; ++i) {
      track.wrenches().wheels[i].f_wheel_in_world = 1e3 * track.states().wheels[i].p_wheel_in_world;
      track.wrenches().wheels[i].n_wheel_in_world = track.states().wheels[i].omega_wheelset_in_world;
    }
    if (!track.send()) return 2;
  }
  return 0;
}

// Vehicle end: times `steps` exchanges after `warmup` untimed ones, round-trip times [s] into rtt; closes.
inline bool timeExchanges(FrameTransport& t, const CouplingConfig& config, long warmup, long steps,
                          std::vector<double>& rtt) {
  VehicleCoupling v(config, t);
  rtt.resize(static_cast<std::size_t>(steps));
  for (long k = 0; k < warmup + steps; ++k) {
    for (int i = 0; i < kWheels; ++i) {
      v.states().wheels[i].p_wheel_in_world = Eigen::Vector3d(1e-3 * static_cast<double>(k), i, 0.445);
      v.states().wheels[i].omega_wheelset_in_world = Eigen::Vector3d(0, 60.0, 0);
    }
    const auto t0 = std::chrono::steady_clock::now();
    const Result r = v.exchange();
    const auto t1 = std::chrono::steady_clock::now();
    if (!r) {
      std::fprintf(stderr, "%s\n", r.message.c_str());
      return false;
    }
    if (k >= warmup) rtt[static_cast<std::size_t>(k - warmup)] = std::chrono::duration<double>(t1 - t0).count();
  }
  v.close();
  return true;
}

// One line: count, median, 99th percentile, mean and largest round trip (us), the label padded to `width`.
inline void report(const char* what, int width, std::vector<double>& rtt) {
  std::sort(rtt.begin(), rtt.end());
  const auto at = [&](double q) { return rtt[static_cast<std::size_t>(q * static_cast<double>(rtt.size() - 1))]; };
  double sum = 0;
  for (double x : rtt) sum += x;
  std::printf("%-*s n %zu  median %8.2f us  p99 %8.2f us  mean %8.2f us  max %9.1f us\n", width, what, rtt.size(),
              1e6 * at(0.5), 1e6 * at(0.99), 1e6 * sum / static_cast<double>(rtt.size()), 1e6 * rtt.back());
  std::fflush(stdout);
}

}  // namespace rail::core::coupling::bench
