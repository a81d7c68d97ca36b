// The handshake names every field in which the two nodes' scenes differ.
#include <gtest/gtest.h>

#include "rail_core/handshake.hpp"

using namespace rail::core;

TEST(Handshake, AgreeingScenesGiveNoMessage) {
  HandshakeInfo a{"/rail_track", "a.yaml", 0x1234, 8, 2e-5, "shm"};
  HandshakeInfo b{"/rail_vehicle", "a.yaml", 0x1234, 8, 2e-5, "shm"};
  EXPECT_EQ(compareHandshake(a, b), "");
}

TEST(Handshake, EachDifferenceIsNamedWithBothValues) {
  HandshakeInfo a{"/rail_track", "a.yaml", 0x1234, 8, 2e-5, "shm"};
  HandshakeInfo b{"/rail_vehicle", "b.yaml", 0xabcd, 4, 1e-5, "service"};
  EXPECT_EQ(compareHandshake(a, b),
            "scene differs from /rail_vehicle's: wheel_count 8 here, 4 there; track_step 2e-05 s here, 1e-05 s "
            "there; transport shm here, service there; scene_hash 0000000000001234 (a.yaml) here, "
            "000000000000abcd (b.yaml) there");
}
