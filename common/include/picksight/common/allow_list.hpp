// Which peers may connect to a port: a list of IPv4 and IPv6 networks, the
// same for the robot port, the Modbus port and any other TCP listener, so
// that an integrator writes one syntax everywhere.
//
// Threading: immutable after parse(); allows() may be called from any thread.
#pragma once

#include <sys/socket.h>

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "picksight/common/result.hpp"

namespace picksight {

enum class AllowListErrc { kBadAddress = 1, kBadPrefix };
const char* errorName(AllowListErrc e);
PICKSIGHT_ERROR_DOMAIN(AllowListErrc, "allow list")

class AllowList {
 public:
  // Everyone is allowed.
  AllowList() = default;

  // "10.0.0.0/8, 192.168.1.7 ::1 fd00::/8": addresses or networks in CIDR
  // notation, separated by commas or spaces. An address without a prefix is
  // that one host. An empty text allows everyone; to allow no one, do not
  // open the port. The error names the entry at fault.
  static Result<AllowList> parse(std::string_view text);

  // Whether a peer (as accept() or getpeername() reports it) may connect.
  // IPv4 peers reaching an IPv6 socket (::ffff:a.b.c.d) match IPv4 entries.
  // Address families other than IPv4 and IPv6 are refused unless the list
  // is empty.
  bool allows(const sockaddr* peer) const;

  bool allowsEveryone() const { return networks_.empty(); }

  // The entries in canonical form ("10.0.0.0/8 ::1/128"), or "any".
  std::string describe() const;

  struct Network {
    bool v6 = false;
    std::array<std::uint8_t, 16> bytes{};  // IPv4 in the first 4
    int prefix = 0;                        // leading bits that must match
  };

 private:
  static bool matches(const Network& network, bool v6, const std::uint8_t* bytes);

  std::vector<Network> networks_;
};

// "a.b.c.d" or "x::y" of a peer, for logs and refusals.
std::string peerAddress(const sockaddr* peer);

}  // namespace picksight

PICKSIGHT_ERROR_ENUM(picksight::AllowListErrc)
