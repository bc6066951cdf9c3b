// The PLC port in process: the Modbus server over real sockets, a device
// whose LOCATE the test controls, libmodbus's client as the PLC. Pins the
// handshake, the register map and the exception replies.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <condition_variable>
#include <cstring>
#include <mutex>

#include "modbus_client.hpp"
#include "picksight/plc/modbus_server.hpp"
#include "picksight/plc/plc_device.hpp"

using namespace picksight;
using namespace picksight::plc;
using picksight::plc::test::ModbusClient;

namespace {
// A LOCATE the test holds until it releases it.
struct FakeCell {
  std::mutex mutex;
  std::condition_variable cv;
  bool hold = false;
  int calls = 0;
  int last_type = -2;
  Result<PlcResult> next = PlcResult{};

  PlcDevice::Picker picker() {
    return [this](int type) -> Result<PlcResult> {
      std::unique_lock<std::mutex> lock(mutex);
      ++calls;
      last_type = type;
      cv.wait(lock, [this] { return !hold; });
      return next;
    };
  }
  void release() {
    {
      std::lock_guard<std::mutex> lock(mutex);
      hold = false;
    }
    cv.notify_all();
  }
};

PlcResult twoParts() {
  PlcResult r;
  r.frame_sequence = 0x12345678;
  r.frame = kFrameRobot;
  r.parts = {{3, 401.25, -233.5, 127.75, 0.96}, {-1, 1.5, 2.5, 359.5, 0}};
  return r;
}

struct Port {
  explicit Port(PlcDeviceOptions device_options = {}, ModbusServerOptions server_options = {}) {
    device = std::make_unique<PlcDevice>(
        device_options, cell.picker(), [] { return kFrameVisionMm; },
        [](const Error& e) { return e.code == std::errc::timed_out ? 20 : 99; });
    server_options.listen.bind_address = "127.0.0.1";
    server_options.listen.port = 0;
    server = std::make_unique<ModbusServer>(server_options, *device);
    device->start();
    server->start();
  }
  ~Port() {
    cell.release();
    server->stop();
    device->stop();
  }
  FakeCell cell;
  std::unique_ptr<PlcDevice> device;
  std::unique_ptr<ModbusServer> server;
};

// Sends raw bytes on a plain socket and returns what comes back (empty
// when the server closed the connection).
std::vector<uint8_t> rawExchange(uint16_t port, const std::vector<uint8_t>& bytes) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  REQUIRE(fd >= 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)) == 0);
  timeval timeout{5, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &timeout, sizeof(timeout));
  REQUIRE(::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL) ==
          static_cast<ssize_t>(bytes.size()));
  uint8_t reply[300];
  const ssize_t n = ::recv(fd, reply, sizeof(reply), 0);
  ::close(fd);
  REQUIRE(n >= 0);  // not a timeout: a reply or a close
  return std::vector<uint8_t>(reply, reply + n);
}
}  // namespace

TEST_CASE("32-bit values in ABCD and CDAB word order", "[plc][registers]") {
  uint16_t r[2];
  putFloat(r, 1.5f, WordOrder::kABCD);
  CHECK(r[0] == 0x3FC0);
  CHECK(r[1] == 0x0000);
  CHECK(modbus_get_float_abcd(r) == 1.5f);  // libmodbus decodes independently
  putFloat(r, -233.5f, WordOrder::kCDAB);
  CHECK(getFloat(r, WordOrder::kCDAB) == -233.5f);
  CHECK(r[1] == 0xC369);
  putU32(r, 0x12345678, WordOrder::kCDAB);
  CHECK(r[0] == 0x5678);
  CHECK(getU32(r, WordOrder::kCDAB) == 0x12345678u);
  CHECK(parseWordOrder("CDAB") == WordOrder::kCDAB);
  CHECK_FALSE(parseWordOrder("BADC"));
}

TEST_CASE("trigger acknowledge busy results-valid handshake", "[plc][handshake]") {
  Port port;
  port.cell.next = twoParts();
  port.cell.hold = true;
  ModbusClient plc(port.server->port());
  CHECK(plc.waitFor(kStatusReady) == kStatusReady);
  CHECK(plc.read(reg::kCalibration) == kFrameVisionMm);

  plc.write(reg::kPartType, 3);
  plc.write(reg::kControl, kControlTrigger);
  // The LOCATE is held: busy and acknowledged, not ready.
  CHECK(plc.status() == (kStatusBusy | kStatusTriggerAck));
  CHECK(plc.read(reg::kTriggerCount) == 1);
  // A trigger edge while busy is counted and ignored.
  plc.write(reg::kControl, 0);
  CHECK(plc.status() == kStatusBusy);
  plc.write(reg::kControl, kControlTrigger);
  CHECK(plc.read(reg::kMissedTriggers) == 1);
  port.cell.release();
  const uint16_t s = plc.waitFor(kStatusResultsValid);
  CHECK((s & (kStatusBusy | kStatusReady | kStatusError)) == 0);
  CHECK(port.cell.calls == 1);
  CHECK(port.cell.last_type == 3);

  CHECK(getU32(plc.read(reg::kFrameSequence, 2).data(), WordOrder::kABCD) == 0x12345678u);
  CHECK(plc.read(reg::kResultFrame) == kFrameRobot);
  CHECK(plc.read(reg::kPartsOffered) == 2);
  const auto parts = plc.parts();
  REQUIRE(parts.size() == 2);
  CHECK(parts[0].type == 3);
  CHECK(parts[0].x == 401.25f);
  CHECK(parts[0].y == -233.5f);
  CHECK(parts[0].rz == 127.75f);
  CHECK(parts[0].score == Approx(0.96f));
  CHECK(parts[1].type == -1);
  CHECK(parts[1].rz == 359.5f);

  // Results stay valid until acknowledged; then ready again.
  plc.write(reg::kControl, 0);
  CHECK((plc.status() & kStatusTriggerAck) == 0);
  CHECK((plc.status() & kStatusResultsValid) != 0);
  plc.acknowledge();
  CHECK(plc.status() == kStatusReady);
  CHECK(plc.read(reg::kPartCount) == 2);  // the data stays until the next trigger
}

TEST_CASE("all types is 65535 and a failed LOCATE sets the error bit and code",
          "[plc][handshake]") {
  Port port;
  port.cell.next = makeError(std::errc::timed_out, "no fresh frame");
  ModbusClient plc(port.server->port());
  const uint16_t s = plc.trigger(kAllTypes);
  CHECK(port.cell.last_type == -1);
  CHECK((s & kStatusError) != 0);
  CHECK((s & kStatusResultsValid) == 0);
  CHECK(plc.read(reg::kErrorCode) == 20);
  CHECK(plc.read(reg::kPartCount) == 0);
  CHECK((plc.status() & kStatusReady) != 0);  // a trigger may follow at once
  plc.write(reg::kControl, kControlClearError);
  CHECK(plc.status() == kStatusReady);
  CHECK(plc.read(reg::kErrorCode) == 0);
  plc.write(reg::kControl, 0);

  // The next good trigger clears a standing error by itself.
  port.cell.next = makeError(std::errc::timed_out, "no fresh frame");
  CHECK((plc.trigger(1) & kStatusError) != 0);
  port.cell.next = twoParts();
  CHECK(plc.trigger(1) == kStatusResultsValid);
  CHECK(plc.read(reg::kErrorCode) == 0);
}

TEST_CASE("bad requests get Modbus exceptions and the port goes on", "[plc][exceptions]") {
  Port port;
  ModbusClient plc(port.server->port());
  // Read-only registers, reserved ones and the end of the map.
  CHECK(plc.writeError(reg::kStatus, 1) == EMBXILADD);
  CHECK(plc.writeError(5, 1) == EMBXILADD);
  CHECK(plc.readError(reg::kCount - 1, 2) == EMBXILADD);
  CHECK(plc.readError(1000, 1) == EMBXILADD);
  const uint16_t two[2] = {0, 7};
  CHECK(modbus_write_registers(plc.ctx(), 2, 2, two) == -1);  // 3 is read-only
  CHECK(errno == EMBXILADD);
  // A job number out of range.
  CHECK(plc.writeError(reg::kJobNumber, 10000) == EMBXILVAL);
  CHECK(plc.read(reg::kJobNumber) == 0);
  // A part type out of range.
  CHECK(plc.writeError(reg::kPartType, 10000) == EMBXILVAL);
  CHECK(plc.read(reg::kPartType) == 0);
  // Coils and discrete inputs are not served.
  uint8_t bits[8];
  CHECK(modbus_read_bits(plc.ctx(), 0, 8, bits) == -1);
  CHECK(errno == EMBXILFUN);
  CHECK(modbus_write_bit(plc.ctx(), 0, 1) == -1);
  CHECK(errno == EMBXILFUN);
  // A write multiple whose byte count disagrees with its quantity.
  const uint8_t bad_count[] = {1, MODBUS_FC_WRITE_MULTIPLE_REGISTERS, 0, 0, 0, 1, 4, 0, 1, 0, 1};
  REQUIRE(modbus_send_raw_request(plc.ctx(), bad_count, sizeof(bad_count)) > 0);
  uint8_t reply[MODBUS_TCP_MAX_ADU_LENGTH];
  CHECK(modbus_receive_confirmation(plc.ctx(), reply) == 9);
  CHECK(reply[7] == (MODBUS_FC_WRITE_MULTIPLE_REGISTERS | 0x80));
  CHECK(reply[8] == MODBUS_EXCEPTION_ILLEGAL_DATA_VALUE);
  // Read input registers (function 4) see the same image, read only.
  uint16_t status = 0;
  CHECK(modbus_read_input_registers(plc.ctx(), reg::kStatus, 1, &status) == 1);
  CHECK(status == kStatusReady);
  // Another unit id: the gateway exception.
  {
    ModbusClient other(port.server->port(), 7);
    CHECK(other.readError(0, 1) == EMBXGTAR);
  }
  // The same connection still works.
  CHECK(plc.status() == kStatusReady);
}

TEST_CASE("a stream that is not Modbus TCP closes its connection only", "[plc][exceptions]") {
  Port port;
  ModbusClient plc(port.server->port());
  // Protocol id 1: not Modbus; the server closes the connection.
  CHECK(rawExchange(port.server->port(), {0, 1, 0, 1, 0, 6, 1, 3, 0, 0, 0, 1}).empty());
  // Framing split across writes and a good request answered.
  const auto reply = rawExchange(port.server->port(), {0, 9, 0, 0, 0, 6, 1, 3, 0, 10, 0, 1});
  REQUIRE(reply.size() == 11);
  CHECK(reply[1] == 9);
  CHECK(reply[7] == MODBUS_FC_READ_HOLDING_REGISTERS);
  CHECK(plc.status() == kStatusReady);
}

TEST_CASE("word order CDAB for every 32-bit value", "[plc][registers]") {
  PlcDeviceOptions options;
  options.word_order = WordOrder::kCDAB;
  Port port(options);
  port.cell.next = twoParts();
  ModbusClient plc(port.server->port());
  CHECK(plc.trigger(3) == kStatusResultsValid);
  const auto parts = plc.parts(WordOrder::kCDAB);
  REQUIRE(parts.size() == 2);
  CHECK(parts[0].x == 401.25f);
  const auto x = plc.read(reg::kFirstPart + reg::kOffsetX, 2);
  CHECK(modbus_get_float_cdab(x.data()) == 401.25f);
  CHECK(getU32(plc.read(reg::kFrameSequence, 2).data(), WordOrder::kCDAB) == 0x12345678u);
}

TEST_CASE("at most 16 parts in the registers and the count of all offered", "[plc][registers]") {
  Port port;
  PlcResult many;
  for (int i = 0; i < 20; ++i) many.parts.push_back({1, double(i), 0, 0, 1});
  port.cell.next = many;
  ModbusClient plc(port.server->port());
  CHECK(plc.trigger(1) == kStatusResultsValid);
  CHECK(plc.read(reg::kPartCount) == reg::kMaxParts);
  CHECK(plc.read(reg::kPartsOffered) == 20);
  CHECK(plc.parts().back().x == 15.0f);
}

TEST_CASE("the heartbeat counts while the PLC polls", "[plc][registers]") {
  Port port;
  ModbusClient plc(port.server->port());
  const uint16_t first = plc.read(reg::kHeartbeat);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (plc.read(reg::kHeartbeat) == first) {
    REQUIRE(std::chrono::steady_clock::now() < deadline);
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

TEST_CASE("peers outside the allow-list and beyond the connection cap are closed",
          "[plc][server]") {
  {
    ModbusServerOptions options;
    options.listen.allow = *AllowList::parse("10.1.2.0/24");
    Port port({}, options);
    modbus_t* ctx = modbus_new_tcp("127.0.0.1", port.server->port());
    modbus_set_response_timeout(ctx, 5, 0);
    REQUIRE(modbus_connect(ctx) == 0);  // accepted, then closed
    uint16_t v = 0;
    CHECK(modbus_read_registers(ctx, 0, 1, &v) == -1);
    modbus_close(ctx);
    modbus_free(ctx);
  }
  ModbusServerOptions options;
  options.listen.max_connections = 2;
  Port port({}, options);
  ModbusClient a(port.server->port());
  ModbusClient b(port.server->port());
  CHECK(a.status() == kStatusReady);
  CHECK(b.status() == kStatusReady);
  modbus_t* ctx = modbus_new_tcp("127.0.0.1", port.server->port());
  modbus_set_response_timeout(ctx, 5, 0);
  REQUIRE(modbus_connect(ctx) == 0);
  uint16_t v = 0;
  CHECK(modbus_read_registers(ctx, 0, 1, &v) == -1);
  modbus_close(ctx);
  modbus_free(ctx);
  CHECK(a.status() == kStatusReady);
}

TEST_CASE("a silent connection is closed after the idle timeout", "[plc][server]") {
  ModbusServerOptions options;
  options.listen.idle_timeout = std::chrono::milliseconds(200);
  Port port({}, options);
  ModbusClient plc(port.server->port());
  CHECK(plc.status() == kStatusReady);
  CHECK(port.server->connections() == 1);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (port.server->connections() != 0) {
    REQUIRE(std::chrono::steady_clock::now() < deadline);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  uint16_t v = 0;
  CHECK(modbus_read_registers(plc.ctx(), 0, 1, &v) == -1);
}
