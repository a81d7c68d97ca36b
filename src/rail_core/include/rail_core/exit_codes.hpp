// Exit codes of the railsim nodes and tools (documented in the README).
#pragma once

namespace rail::core {

enum ExitCode : int {
  kExitOk = 0,           // finished (or validated) normally
  kExitBadInput = 2,     // the scene or a data file was refused; the message names the file and field
  kExitPeerRefused = 3,  // the peer runs another scene (handshake refused); the message names what differs
  kExitPeerTimeout = 4,  // the peer never answered or stopped answering within its timeout
  kExitInterrupted = 5,  // stopped by SIGINT/SIGTERM or by the ROS master going away
  kExitInternal = 6,     // an unexpected error inside the program (a bug): please report it
  kExitDerailed = 7,     // the vehicle derailed (or a wheel reached the track's end): the message names wheel, s, t
  kExitNumerical = 8,    // the integration failed or the state became non-finite: the message names where, when
  kExitWriteFailed = 9,  // an output could not be written (disk full, unwritable): the message names the file and why
};

}  // namespace rail::core
