// Peer allow-lists: parsing, errors that name the entry, and matching of
// IPv4, IPv6 and IPv4-mapped peers at prefix boundaries.
#include "picksight/common/allow_list.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>

#include <catch2/catch.hpp>

namespace picksight {
namespace {

sockaddr_storage peer(const char* text) {
  sockaddr_storage storage{};
  auto* v4 = reinterpret_cast<sockaddr_in*>(&storage);
  auto* v6 = reinterpret_cast<sockaddr_in6*>(&storage);
  if (::inet_pton(AF_INET, text, &v4->sin_addr) == 1) {
    v4->sin_family = AF_INET;
  } else {
    REQUIRE(::inet_pton(AF_INET6, text, &v6->sin6_addr) == 1);
    v6->sin6_family = AF_INET6;
  }
  return storage;
}

bool allows(const AllowList& list, const char* text) {
  const auto storage = peer(text);
  return list.allows(reinterpret_cast<const sockaddr*>(&storage));
}

TEST_CASE("An empty allow-list lets everyone in", "[common]") {
  const auto list = AllowList::parse(" , ");
  REQUIRE(list);
  CHECK(list->allowsEveryone());
  CHECK(allows(*list, "203.0.113.9"));
  CHECK(allows(*list, "2001:db8::1"));
  CHECK(list->describe() == "any");
}

TEST_CASE("Networks match exactly their prefix bits", "[common]") {
  const auto list = AllowList::parse("192.168.10.0/23 10.1.2.3\tfd00::/12");
  REQUIRE(list);
  CHECK(allows(*list, "192.168.10.0"));
  CHECK(allows(*list, "192.168.11.255"));
  CHECK_FALSE(allows(*list, "192.168.12.0"));
  CHECK_FALSE(allows(*list, "192.168.9.255"));
  CHECK(allows(*list, "10.1.2.3"));
  CHECK_FALSE(allows(*list, "10.1.2.4"));
  CHECK(allows(*list, "fd0f:ffff::1"));
  CHECK_FALSE(allows(*list, "fd10::1"));
  CHECK_FALSE(allows(*list, "::1"));
}

TEST_CASE("IPv4 peers on a dual-stack socket match IPv4 entries only", "[common]") {
  const auto list = AllowList::parse("127.0.0.0/8");
  REQUIRE(list);
  CHECK(allows(*list, "::ffff:127.0.0.1"));
  CHECK_FALSE(allows(*list, "::ffff:128.0.0.1"));
  const auto v6_only = AllowList::parse("::/0");
  REQUIRE(v6_only);
  CHECK_FALSE(allows(*v6_only, "::ffff:127.0.0.1"));
  CHECK(allows(*v6_only, "::1"));
}

TEST_CASE("Host bits below the prefix are dropped from the description", "[common]") {
  const auto list = AllowList::parse("10.9.8.7/8,2001:db8::ff/64, 0.0.0.0/0");
  REQUIRE(list);
  CHECK(list->describe() == "10.0.0.0/8 2001:db8::/64 0.0.0.0/0");
  CHECK(allows(*list, "198.51.100.1"));
}

TEST_CASE("A bad entry is refused with its text in the message", "[common]") {
  for (const char* text : {"10.0.0.300", "10.0.0.0/33", "::1/129", "10.0.0.0/-1", "10.0.0.0/",
                           "host.example", "10.0.0.0/8/8"}) {
    INFO(text);
    const auto list = AllowList::parse(std::string("127.0.0.1 ") + text);
    REQUIRE_FALSE(list);
    CHECK(list.error().message.find(text) != std::string::npos);
  }
  CHECK(AllowList::parse("10.0.0.0/33").error().code == AllowListErrc::kBadPrefix);
  CHECK(AllowList::parse("nobody").error().code == AllowListErrc::kBadAddress);
}

TEST_CASE("Peers are printed without the IPv4-mapped prefix", "[common]") {
  const auto mapped = peer("::ffff:192.0.2.5");
  CHECK(peerAddress(reinterpret_cast<const sockaddr*>(&mapped)) == "192.0.2.5");
  const auto v6 = peer("2001:db8::5");
  CHECK(peerAddress(reinterpret_cast<const sockaddr*>(&v6)) == "2001:db8::5");
}

}  // namespace
}  // namespace picksight
