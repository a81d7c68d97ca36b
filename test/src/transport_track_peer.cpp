// The synthetic track node of the transport test (started by test_cosim_transports, one per run): serves
// the co-simulation over one transport with TrackCoupling, checks that every step arrives once and in
// order with the states g(t_k) exactly, answers f(step, states), and ends when the vehicle closes.
//
// usage: transport_track_peer <service|topic|shm> <name prefix> <shm run id> <vehicle node> <steps expected>
//        [__name:=<node name>]
// Exit code: 0 all steps as expected and the vehicle closed; 1 an exchange failed; 2 a step or a state
// differed; 3 set-up failed.
#include <cstdio>
#include <cstdlib>
#include <string>

#include <ros/ros.h>

#include "cosim_synthetic.hpp"

using namespace rail::core::coupling;
using namespace railsim_test;

int main(int argc, char** argv) {
  ros::init(argc, argv, "transport_track_peer", ros::init_options::NoSigintHandler);
  if (argc < 6) {
    std::fprintf(stderr, "usage: transport_track_peer <service|topic|shm> <prefix> <run id> <vehicle node> <steps>\n");
    return 3;
  }
  const std::string kind = argv[1];
  RunNames names{argv[2], argv[3]};
  const std::string vehicle_node = argv[4];
  const long steps_expected = std::atol(argv[5]);
  ros::NodeHandle nh;
  const std::string self = ros::this_node::getName();

  std::unique_ptr<FrameTransport> transport;
  try {
    transport = makeTransport(kind, Role::kTrack, names, nh, vehicle_node);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s: %s\n", self.c_str(), e.what());
    return 3;
  }
  TrackCoupling track(config(5.0), *transport);
  WheelState expected_state;
  long received = 0;
  int code = 0;
  for (;;) {
    // The first step may wait for the vehicle's start-up; later ones the exchange timeout.
    const Result r = received == 0 ? track.receive(Clock::now() + std::chrono::seconds(30)) : track.receive();
    if (r.status == Status::kPeerClosed) break;  // the normal end
    if (!r) {
      std::fprintf(stderr, "%s: %s\n", self.c_str(), r.message.c_str());
      code = 1;
      break;
    }
    const WheelStateFrame& s = track.states();
    if (s.step != static_cast<std::uint64_t>(received) || s.count != static_cast<std::uint32_t>(kWheels)) {
      std::fprintf(stderr, "%s: step %llu with %u wheels received, step %ld with %d expected\n", self.c_str(),
                   static_cast<unsigned long long>(s.step), s.count, received, kWheels);
      code = 2;
      break;
    }
    for (int i = 0; i < kWheels; ++i) {
      wheelStateAt(static_cast<double>(s.step) * kTrackStep, i, expected_state);
      if (!same(s.wheels[i], expected_state)) {
        std::fprintf(stderr, "%s: step %ld wheel %d: states differ from g(t_k)\n", self.c_str(), received, i);
        code = 2;
      }
      wrenchFor(s.step, s.wheels[i], track.wrenches().wheels[i]);
    }
    if (code != 0) break;
    ++received;
    const Result w = track.send();
    if (!w) {
      std::fprintf(stderr, "%s: %s\n", self.c_str(), w.message.c_str());
      code = 1;
      break;
    }
  }
  if (code == 0 && received != steps_expected) {
    std::fprintf(stderr, "%s: %ld steps received, %ld expected\n", self.c_str(), received, steps_expected);
    code = 2;
  }
  if (code == 0)
    std::printf("%s: %ld steps over %s, each once and in order, states exact\n", self.c_str(), received, kind.c_str());
  track.close();
  transport.reset();
  ros::shutdown();
  return code;
}
