// Pins the GigE host tuning helpers: the socket buffer the kernel grants and
// the warning, with the command to run, when it is capped.
#include <catch2/catch.hpp>

#include <fstream>
#include <string>

#include "aravis/gige_tuning.hpp"

using picksight::video::grantedSocketBuffer;
using picksight::video::socketBufferWarning;

TEST_CASE("gige socket buffer: granted up to rmem_max, a capped one named with the sysctl",
          "[aravis]") {
  std::ifstream in("/proc/sys/net/core/rmem_max");
  size_t limit = 0;
  REQUIRE(in >> limit);
  CHECK(grantedSocketBuffer(limit + 4096) == limit);
  CHECK(grantedSocketBuffer(limit / 2) == limit / 2);

  const std::string warning = socketBufferWarning(4u << 20, 212992);
  CHECK_THAT(warning, Catch::Contains("208 KiB") && Catch::Contains("4096 KiB") &&
                          Catch::Contains("sysctl -w net.core.rmem_max=4194304"));
  CHECK(socketBufferWarning(4u << 20, 4u << 20).empty());
}
