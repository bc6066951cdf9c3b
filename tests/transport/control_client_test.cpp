// Pins the control client: replies and server errors as values, and a silent
// server giving ControlErrc::kNoReply without leaving the client stuck.
#include <atomic>
#include <chrono>
#include <optional>
#include <string>
#include <thread>

#include <catch2/catch.hpp>
#include <zmq.hpp>

#include "picksight/transport/control_client.hpp"

using namespace std::chrono_literals;
namespace proto = picksight::proto;
using picksight::transport::ControlClient;

namespace {

proto::ControlRequest listRequest() {
  proto::ControlRequest r;
  r.mutable_list_cameras();
  return r;
}

proto::ControlReply cameraList(const std::string& name) {
  proto::ControlReply reply;
  reply.mutable_error()->set_code(proto::Error::OK);
  reply.mutable_list_cameras()->add_cameras()->set_name(name);
  return reply;
}

zmq::socket_t boundRep(zmq::context_t& context, std::string* endpoint) {
  zmq::socket_t rep(context, zmq::socket_type::rep);
  rep.set(zmq::sockopt::linger, 0);
  rep.bind("tcp://127.0.0.1:*");
  *endpoint = rep.get(zmq::sockopt::last_endpoint);
  return rep;
}

// Receives one request on `rep` and answers it with `reply` bytes. Returns
// the request, or an empty one if none came within 10 s.
proto::ControlRequest answerOnce(zmq::socket_t& rep, const std::string& reply_bytes) {
  proto::ControlRequest request;
  zmq::pollitem_t item{rep.handle(), 0, ZMQ_POLLIN, 0};
  if (zmq::poll(&item, 1, 10000ms) == 0) return request;
  zmq::message_t bytes;
  if (!rep.recv(bytes)) return request;
  request.ParseFromArray(bytes.data(), static_cast<int>(bytes.size()));
  rep.send(zmq::buffer(reply_bytes), zmq::send_flags::none);
  return request;
}

}  // namespace

TEST_CASE("ControlClient returns the reply of a server that answers OK", "[common]") {
  zmq::context_t context;
  std::string endpoint;
  zmq::socket_t rep = boundRep(context, &endpoint);
  ControlClient client(context, endpoint, 10000ms);
  CHECK(client.endpoint() == endpoint);
  proto::ControlRequest received;
  std::thread server([&] { received = answerOnce(rep, cameraList("cam0").SerializeAsString()); });
  auto reply = client.call(listRequest());
  server.join();
  CHECK(received.has_list_cameras());
  REQUIRE(reply);
  REQUIRE(reply->list_cameras().cameras_size() == 1);
  CHECK(reply->list_cameras().cameras(0).name() == "cam0");
}

TEST_CASE("ControlClient turns a server error into an Error with its code and text", "[common]") {
  zmq::context_t context;
  std::string endpoint;
  zmq::socket_t rep = boundRep(context, &endpoint);
  ControlClient client(context, endpoint, 10000ms);
  proto::ControlReply error_reply;
  error_reply.mutable_error()->set_code(proto::Error::UNKNOWN_CAMERA);
  error_reply.mutable_error()->set_text("unknown camera 'camX'");
  std::thread server([&] { answerOnce(rep, error_reply.SerializeAsString()); });
  auto reply = client.call(listRequest());
  server.join();
  REQUIRE_FALSE(reply);
  CHECK(reply.error().code == picksight::transport::ControlErrc::kUnknownCamera);
  CHECK(reply.error().message == "unknown camera 'camX'");
}

TEST_CASE("ControlClient reports a malformed reply as INTERNAL", "[common]") {
  zmq::context_t context;
  std::string endpoint;
  zmq::socket_t rep = boundRep(context, &endpoint);
  ControlClient client(context, endpoint, 10000ms);
  std::thread server([&] { answerOnce(rep, std::string("\xff\xff\xff\xff", 4)); });
  auto reply = client.call(listRequest());
  server.join();
  REQUIRE_FALSE(reply);
  CHECK(reply.error().code == picksight::transport::ControlErrc::kInternal);
}

TEST_CASE("ControlClient times out on a silent server and works again afterwards", "[common]") {
  zmq::context_t context;
  std::string endpoint;
  zmq::socket_t rep = boundRep(context, &endpoint);
  const auto timeout = 500ms;
  ControlClient client(context, endpoint, timeout);

  // The REP socket receives the request but nobody answers it.
  const auto start = std::chrono::steady_clock::now();
  auto first = client.call(listRequest());
  const auto elapsed = std::chrono::steady_clock::now() - start;
  REQUIRE_FALSE(first);
  CHECK(first.error().code == picksight::transport::ControlErrc::kNoReply);
  CHECK_THAT(first.error().message, Catch::Contains(endpoint));
  // Bounded by the timeout, with a generous allowance for a loaded machine.
  CHECK(elapsed < timeout + 10s);

  // Now a server answers every request: first the abandoned one (that answer
  // goes nowhere), then the client's next request.
  std::atomic<bool> stop{false};
  std::thread server([&] {
    const std::string bytes = cameraList("cam7").SerializeAsString();
    while (!stop) {
      zmq::pollitem_t item{rep.handle(), 0, ZMQ_POLLIN, 0};
      if (zmq::poll(&item, 1, 50ms) == 0) continue;
      zmq::message_t request;
      if (!rep.recv(request)) continue;
      rep.send(zmq::buffer(bytes), zmq::send_flags::none);
    }
  });
  // A very loaded machine may exceed the short timeout once more: retrying is
  // what a caller does, and each retry must find the client usable.
  std::optional<picksight::Result<proto::ControlReply>> second;
  for (int attempt = 0; attempt < 20; ++attempt) {
    second.emplace(client.call(listRequest()));
    if (second->ok() || second->error().code != picksight::transport::ControlErrc::kNoReply) break;
  }
  stop = true;
  server.join();
  REQUIRE(second);
  REQUIRE(second->ok());
  REQUIRE(second->value().list_cameras().cameras_size() == 1);
  CHECK(second->value().list_cameras().cameras(0).name() == "cam7");
}
