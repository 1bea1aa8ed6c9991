// The DBC description of the protocol, generated from the message definitions
// (firmware/protocol/messages.h) so that CAN tools (candump with a decoder, SavvyCAN,
// Wireshark's DBC support, python-can/cantools/canmatrix) read our frames. One message
// per function code and node (Name_J1 … Name_J8); the committed maestro_jc.dbc is this
// output, and a test keeps the two identical.
#pragma once

#include <string>

namespace mjc::host {

std::string GenerateDbc();

}  // namespace mjc::host
