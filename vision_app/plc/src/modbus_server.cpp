// Modbus TCP server: libmodbus replies; one poll() loop frames
// the requests of every connection, with a bound on connections, on bytes
// per request and on idle time.
#include "picksight/plc/modbus_server.hpp"

#include <poll.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstring>
#include <list>
#include <stdexcept>
#include <vector>

#include "picksight/common/log.hpp"

namespace picksight::plc {
namespace {
using Clock = std::chrono::steady_clock;

struct Connection {
  TcpListener::Connection link;
  std::vector<uint8_t> pending;  // bytes of the request being received
  Clock::time_point last_request;
};
}  // namespace

// A refused PLC is closed without a word: Modbus has no reply for it.
ModbusServer::ModbusServer(ModbusServerOptions options, PlcDevice& device)
    : options_(std::move(options)), device_(device), listener_("Modbus port", options_.listen) {
  replier_ = modbus_new_tcp("127.0.0.1", 502);  // only its socket is ever set
  if (!replier_) throw std::runtime_error("Modbus server: out of memory");
}

ModbusServer::~ModbusServer() {
  stop();
  modbus_free(replier_);
}

void ModbusServer::start() {
  if (thread_.joinable()) return;
  stop_ = false;
  thread_ = std::thread([this] { loop(); });
}

void ModbusServer::stop() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

void ModbusServer::loop() {
  std::list<Connection> open;
  const auto close = [&](std::list<Connection>::iterator it) { return open.erase(it); };
  std::vector<pollfd> polled;
  uint8_t chunk[512];
  while (!stop_) {
    polled.assign(1, pollfd{listener_.fd(), POLLIN, 0});
    for (const auto& c : open) polled.push_back(pollfd{c.link.fd(), POLLIN, 0});
    const int ready = ::poll(polled.data(), polled.size(), 100);
    if (ready < 0 && errno != EINTR) {
      logError("Modbus server: poll: ", std::strerror(errno));
      break;
    }
    const auto now = Clock::now();
    // Connections first: polled[1..] are in the order of `open`.
    size_t index = 1;
    for (auto it = open.begin(); it != open.end(); ++index) {
      const short events = ready > 0 ? polled[index].revents : 0;
      if (events == 0) {
        const auto idle = options_.listen.idle_timeout;
        const bool expired = idle.count() > 0 && now - it->last_request > idle;
        it = expired ? close(it) : std::next(it);
        continue;
      }
      const ssize_t n = ::recv(it->link.fd(), chunk, sizeof(chunk), MSG_DONTWAIT);
      if (n < 0 && (errno == EINTR || errno == EAGAIN)) {
        ++it;
        continue;
      }
      if (n <= 0) {
        it = close(it);
        continue;
      }
      it->pending.insert(it->pending.end(), chunk, chunk + n);
      bool keep = true;
      while (keep) {
        const auto length = aduLength(it->pending.data(), it->pending.size());
        if (!length) {
          keep = false;  // not Modbus TCP: the stream cannot be followed
          break;
        }
        if (*length == 0) break;
        it->last_request = now;
        modbus_set_socket(replier_, it->link.fd());
        keep = device_.handle(replier_, it->pending.data(), *length);
        it->pending.erase(it->pending.begin(),
                          it->pending.begin() + static_cast<std::ptrdiff_t>(*length));
      }
      modbus_set_socket(replier_, -1);
      it = keep ? std::next(it) : close(it);
    }
    if (ready > 0 && (polled[0].revents & POLLIN)) {
      if (auto accepted = listener_.accept())
        open.push_back(Connection{std::move(*accepted), {}, now});
    }
  }
  while (!open.empty()) close(open.begin());
}

}  // namespace picksight::plc
