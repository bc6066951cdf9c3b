// Parsing and matching of peer allow-lists.
#include "picksight/common/allow_list.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>

#include <cstring>

#include "picksight/common/text.hpp"

namespace picksight {

const char* errorName(AllowListErrc e) {
  switch (e) {
    case AllowListErrc::kBadAddress:
      return "bad address";
    case AllowListErrc::kBadPrefix:
      return "bad prefix";
  }
  return "unknown";
}

// One entry: "a.b.c.d", "a.b.c.d/n", "x::y" or "x::y/n".
static Result<AllowList::Network> parseNetwork(std::string_view entry) {
  AllowList::Network network;
  const auto slash = entry.find('/');
  const std::string address(entry.substr(0, slash));
  int max_prefix = 32;
  if (::inet_pton(AF_INET, address.c_str(), network.bytes.data()) != 1) {
    if (::inet_pton(AF_INET6, address.c_str(), network.bytes.data()) != 1) {
      return makeError(AllowListErrc::kBadAddress,
                       "'" + std::string(entry) + "' is not an IPv4 or IPv6 address or network");
    }
    network.v6 = true;
    max_prefix = 128;
  }
  network.prefix = max_prefix;
  if (slash != std::string_view::npos) {
    const auto bits = parseInt(entry.substr(slash + 1));
    if (!bits || *bits < 0 || *bits > max_prefix) {
      return makeError(
          AllowListErrc::kBadPrefix,
          "'" + std::string(entry) + "': the prefix must be 0.." + std::to_string(max_prefix));
    }
    network.prefix = static_cast<int>(*bits);
  }
  // Host bits below the prefix are ignored when matching; clear them so that
  // describe() shows the network actually allowed.
  for (int bit = network.prefix; bit < max_prefix; ++bit) {
    network.bytes[static_cast<std::size_t>(bit / 8)] &=
        static_cast<std::uint8_t>(~(0x80u >> (bit % 8)));
  }
  return network;
}

Result<AllowList> AllowList::parse(std::string_view text) {
  AllowList list;
  for (const auto entry : splitFields(text, ", \t\r\n")) {
    auto network = parseNetwork(entry);
    if (!network) return network.error();
    list.networks_.push_back(*network);
  }
  return list;
}

bool AllowList::matches(const Network& network, bool v6, const std::uint8_t* bytes) {
  if (network.v6 != v6) return false;
  const int whole = network.prefix / 8;
  if (std::memcmp(network.bytes.data(), bytes, static_cast<std::size_t>(whole)) != 0) return false;
  const int rest = network.prefix % 8;
  if (rest == 0) return true;
  const auto mask = static_cast<std::uint8_t>(0xffu << (8 - rest));
  return (network.bytes[static_cast<std::size_t>(whole)] & mask) == (bytes[whole] & mask);
}

bool AllowList::allows(const sockaddr* peer) const {
  if (networks_.empty()) return true;
  if (peer == nullptr) return false;
  bool v6 = false;
  const std::uint8_t* bytes = nullptr;
  if (peer->sa_family == AF_INET) {
    bytes = reinterpret_cast<const std::uint8_t*>(
        &reinterpret_cast<const sockaddr_in*>(peer)->sin_addr.s_addr);
  } else if (peer->sa_family == AF_INET6) {
    const auto& address = reinterpret_cast<const sockaddr_in6*>(peer)->sin6_addr;
    bytes = address.s6_addr;
    v6 = !IN6_IS_ADDR_V4MAPPED(&address);
    if (!v6) bytes += 12;  // ::ffff:a.b.c.d is an IPv4 peer on a dual-stack socket
  } else {
    return false;
  }
  for (const auto& network : networks_) {
    if (matches(network, v6, bytes)) return true;
  }
  return false;
}

std::string AllowList::describe() const {
  if (networks_.empty()) return "any";
  std::string out;
  for (const auto& network : networks_) {
    char text[INET6_ADDRSTRLEN] = {};
    ::inet_ntop(network.v6 ? AF_INET6 : AF_INET, network.bytes.data(), text, sizeof text);
    if (!out.empty()) out += ' ';
    out += text;
    out += '/' + std::to_string(network.prefix);
  }
  return out;
}

std::string peerAddress(const sockaddr* peer) {
  char text[INET6_ADDRSTRLEN] = {};
  if (peer == nullptr) return "?";
  if (peer->sa_family == AF_INET) {
    ::inet_ntop(AF_INET, &reinterpret_cast<const sockaddr_in*>(peer)->sin_addr, text, sizeof text);
  } else if (peer->sa_family == AF_INET6) {
    const auto& address = reinterpret_cast<const sockaddr_in6*>(peer)->sin6_addr;
    if (IN6_IS_ADDR_V4MAPPED(&address)) {
      ::inet_ntop(AF_INET, address.s6_addr + 12, text, sizeof text);
    } else {
      ::inet_ntop(AF_INET6, &address, text, sizeof text);
    }
  } else {
    return "family " + std::to_string(peer->sa_family);
  }
  return text;
}

}  // namespace picksight
