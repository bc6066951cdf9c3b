// CURVE keys and the ZAP handler: key files and their checks, and real
// sockets of one process (listed, unlisted and plain clients of a CURVE PUB).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

#include "picksight/transport/control_client.hpp"
#include "picksight/transport/curve_keys.hpp"
#include "picksight/transport/curve_server.hpp"
#include "temp_dir.hpp"

using namespace picksight;
using namespace picksight::transport;
using namespace std::chrono_literals;

namespace {

// Writes NAME.key and NAME.key_secret (0600) into `dir`; the pair.
CurveKeyPair writePair(const test::TempDir& dir, const std::string& name) {
  auto keys = generateKeyPair();
  REQUIRE(keys);
  dir.write(name + ".key", publicKeyFileText(*keys));
  const std::string secret = dir.write(name + ".key_secret", secretKeyFileText(*keys));
  REQUIRE(::chmod(secret.c_str(), 0600) == 0);
  return *keys;
}

// Reads whatever arrived on `socket` without waiting; the messages counted.
int drain(zmq::socket_t& socket) {
  int n = 0;
  zmq::message_t message;
  while (socket.recv(message, zmq::recv_flags::dontwait)) ++n;
  return n;
}

}  // namespace

TEST_CASE("A key pair survives its files", "[transport][curve]") {
  test::TempDir dir;
  const CurveKeyPair keys = writePair(dir, "server");
  auto pair = loadKeyPair(dir.file("server.key_secret"));
  REQUIRE(pair);
  CHECK(pair->public_key == keys.public_key);
  CHECK(pair->secret_key == keys.secret_key);
  auto public_key = loadPublicKey(dir.file("server.key"));
  REQUIRE(public_key);
  CHECK(*public_key == keys.public_key);
  CHECK(public_key->size() == kZ85KeyLength);
}

TEST_CASE("A secret key file others may read is refused naming the file", "[transport][curve]") {
  test::TempDir dir;
  writePair(dir, "server");
  const std::string path = dir.file("server.key_secret");
  for (mode_t mode : {0640, 0604, 0644, 0610}) {
    REQUIRE(::chmod(path.c_str(), mode) == 0);
    auto pair = loadKeyPair(path);
    REQUIRE_FALSE(pair);
    CHECK(pair.error().code == CurveErrc::kKeyFileTooOpen);
    CHECK_THAT(pair.error().message, Catch::Contains(path) && Catch::Contains("chmod 600"));
  }
  REQUIRE(::chmod(path.c_str(), 0400) == 0);
  CHECK(loadKeyPair(path));
}

TEST_CASE("Malformed key files are errors naming the file", "[transport][curve]") {
  test::TempDir dir;
  const CurveKeyPair keys = writePair(dir, "good");
  const CurveKeyPair other = *generateKeyPair();
  struct Case {
    const char* what;
    std::string text;
  };
  const std::vector<Case> cases = {
      {"empty", ""},
      {"short key", "public-key = \"abc\"\nsecret-key = \"" + keys.secret_key + "\"\n"},
      {"not Z85",
       "public-key = \"" + std::string(40, '~') + "\"\nsecret-key = \"" + keys.secret_key + "\"\n"},
      {"public only", publicKeyFileText(keys)},
      {"mismatched pair",
       "public-key = \"" + other.public_key + "\"\nsecret-key = \"" + keys.secret_key + "\"\n"},
      {"two public keys", "public-key = \"" + keys.public_key + "\"\n" + secretKeyFileText(keys)},
      {"binary", std::string("\0\x01\xff garbage", 11)},
  };
  for (const auto& c : cases) {
    INFO(c.what);
    const std::string path = dir.write("bad.key_secret", c.text);
    REQUIRE(::chmod(path.c_str(), 0600) == 0);
    auto pair = loadKeyPair(path);
    REQUIRE_FALSE(pair);
    CHECK(pair.error().code == CurveErrc::kBadKeyFile);
    CHECK_THAT(pair.error().message, Catch::Contains(path));
  }
  auto missing = loadPublicKey(dir.file("absent.key"));
  REQUIRE_FALSE(missing);
  CHECK_THAT(missing.error().message, Catch::Contains("absent.key"));
  auto directory = loadPublicKey(dir.path().string());
  REQUIRE_FALSE(directory);
  CHECK(directory.error().code == CurveErrc::kBadKeyFile);
  auto huge = loadPublicKey(dir.write("huge.key", std::string(1 << 20, '#')));
  REQUIRE_FALSE(huge);
  CHECK_THAT(huge.error().message, Catch::Contains("too large"));
}

TEST_CASE("An allow-list is a directory of key files or one file of keys", "[transport][curve]") {
  test::TempDir dir;
  std::filesystem::create_directory(dir.path() / "clients");
  test::TempDir clients;
  const CurveKeyPair a = writePair(clients, "a");
  const CurveKeyPair b = writePair(clients, "b");
  auto from_dir = loadAllowList(clients.path().string());
  REQUIRE(from_dir);
  CHECK(*from_dir == std::set<std::string>{a.public_key, b.public_key});

  const std::string file = dir.write("allowed", "# cell 3\npublic-key = \"" + a.public_key +
                                                    "\"\n\npublic-key = " + b.public_key + "\n");
  auto from_file = loadAllowList(file);
  REQUIRE(from_file);
  CHECK(*from_file == std::set<std::string>{a.public_key, b.public_key});

  auto empty = loadAllowList((dir.path() / "clients").string());
  REQUIRE_FALSE(empty);
  CHECK_THAT(empty.error().message, Catch::Contains("admit nobody"));
  clients.write("c.key", "public-key = \"nonsense\"\n");
  auto bad = loadAllowList(clients.path().string());
  REQUIRE_FALSE(bad);
  CHECK_THAT(bad.error().message, Catch::Contains(clients.file("c.key")));
}

TEST_CASE("Only allow-listed CURVE clients receive from a CURVE server", "[transport][curve]") {
  test::TempDir dir;
  const CurveKeyPair server_keys = writePair(dir, "server");
  writePair(dir, "listed");
  const CurveKeyPair stranger = *generateKeyPair();
  const std::string allow =
      dir.write("allowed", publicKeyFileText(*loadKeyPair(dir.file("listed.key_secret"))));
  zmq::context_t context;
  auto curve = CurveServer::start(context, dir.file("server.key_secret"), allow);
  REQUIRE(curve);
  REQUIRE((*curve)->restricted());
  CHECK((*curve)->publicKey() == server_keys.public_key);
  // A second handler on the same context is refused, not silently ignored.
  auto second = CurveServer::start(context, dir.file("server.key_secret"), allow);
  REQUIRE_FALSE(second);
  CHECK(second.error().code == CurveErrc::kZapHandlerTaken);

  zmq::socket_t pub(context, zmq::socket_type::pub);
  pub.set(zmq::sockopt::linger, 0);
  (*curve)->secure(pub);
  pub.bind("tcp://127.0.0.1:*");
  const std::string endpoint = pub.get(zmq::sockopt::last_endpoint);

  auto subscriber = [&](const std::optional<CurveClientKeys>& keys) {
    zmq::socket_t sub(context, zmq::socket_type::sub);
    sub.set(zmq::sockopt::linger, 0);
    sub.set(zmq::sockopt::subscribe, "");
    secureClientSocket(sub, keys);
    sub.connect(endpoint);
    return sub;
  };
  // The ones that must get nothing connect first: they have at least the
  // listed client's time.
  zmq::socket_t unlisted = subscriber(CurveClientKeys{stranger, server_keys.public_key});
  zmq::socket_t plain = subscriber(std::nullopt);
  auto listed_keys = loadClientKeys(dir.file("listed.key_secret"), dir.file("server.key"));
  REQUIRE(listed_keys);
  zmq::socket_t listed = subscriber(*listed_keys);

  int listed_got = 0, unlisted_got = 0, plain_got = 0;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < deadline &&
         (listed_got < 20 || (*curve)->refused() == 0)) {
    pub.send(zmq::str_buffer("frame"), zmq::send_flags::none);
    zmq::pollitem_t items[] = {{listed.handle(), 0, ZMQ_POLLIN, 0}};
    zmq::poll(items, 1, 20ms);
    listed_got += drain(listed);
    unlisted_got += drain(unlisted);
    plain_got += drain(plain);
  }
  CHECK(listed_got >= 20);
  CHECK((*curve)->admitted() >= 1);
  CHECK((*curve)->refused() >= 1);
  CHECK(unlisted_got == 0);
  CHECK(plain_got == 0);
}

TEST_CASE("Without an allow-list CURVE encrypts but admits any key", "[transport][curve]") {
  test::TempDir dir;
  const CurveKeyPair server_keys = writePair(dir, "server");
  zmq::context_t context;
  auto curve = CurveServer::start(context, dir.file("server.key_secret"), "");
  REQUIRE(curve);
  CHECK_FALSE((*curve)->restricted());
  zmq::socket_t rep(context, zmq::socket_type::rep);
  rep.set(zmq::sockopt::linger, 0);
  (*curve)->secure(rep);
  rep.bind("tcp://127.0.0.1:*");
  zmq::socket_t req(context, zmq::socket_type::req);
  req.set(zmq::sockopt::linger, 0);
  // Any fresh pair: the server key file alone is enough.
  auto keys = loadClientKeys("", dir.file("server.key"));
  REQUIRE(keys);
  secureClientSocket(req, *keys);
  req.connect(rep.get(zmq::sockopt::last_endpoint));
  req.send(zmq::str_buffer("ping"), zmq::send_flags::none);
  zmq::pollitem_t item{rep.handle(), 0, ZMQ_POLLIN, 0};
  REQUIRE(zmq::poll(&item, 1, 10s) == 1);
  zmq::message_t message;
  REQUIRE(rep.recv(message));
  CHECK(message.to_string() == "ping");
}

TEST_CASE("A control client refused by CURVE gets no reply and never blocks",
          "[transport][curve]") {
  test::TempDir dir;
  const CurveKeyPair server_keys = writePair(dir, "server");
  const CurveKeyPair listed = writePair(dir, "listed");
  zmq::context_t context;
  auto curve = CurveServer::start(context, dir.file("server.key_secret"), dir.file("listed.key"));
  REQUIRE(curve);
  zmq::socket_t router(context, zmq::socket_type::router);
  router.set(zmq::sockopt::linger, 0);
  (*curve)->secure(router);
  router.bind("tcp://127.0.0.1:*");
  const std::string endpoint = router.get(zmq::sockopt::last_endpoint);
  proto::ControlRequest request;
  request.mutable_list_cameras();
  ControlClient stranger(context, endpoint, 300ms,
                         CurveClientKeys{*generateKeyPair(), server_keys.public_key});
  ControlClient plain(context, endpoint, 300ms);
  // A call after the refusal is the one that could block on a socket left
  // without a connection: wait for the refusal first.
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while ((*curve)->refused() == 0 && std::chrono::steady_clock::now() < deadline) {
    zmq::pollitem_t none{router.handle(), 0, ZMQ_POLLIN, 0};
    zmq::poll(&none, 1, 10ms);
  }
  REQUIRE((*curve)->refused() >= 1);
  for (int i = 0; i < 4; ++i) {
    auto refused = stranger.call(request);
    REQUIRE_FALSE(refused);
    CHECK(refused.error().code == ControlErrc::kNoReply);
    auto ignored = plain.call(request);
    REQUIRE_FALSE(ignored);
    CHECK(ignored.error().code == ControlErrc::kNoReply);
  }
  CHECK((*curve)->refused() >= 1);
  // The listed client reaches the same socket (positive control).
  zmq::socket_t dealer(context, zmq::socket_type::req);
  dealer.set(zmq::sockopt::linger, 0);
  secureClientSocket(dealer, CurveClientKeys{listed, server_keys.public_key});
  dealer.connect(endpoint);
  dealer.send(zmq::str_buffer("hello"), zmq::send_flags::none);
  zmq::pollitem_t item{router.handle(), 0, ZMQ_POLLIN, 0};
  CHECK(zmq::poll(&item, 1, 10s) == 1);
}

TEST_CASE("The refused keys counted for the log are bounded: after 1024 the count starts over",
          "[transport][curve]") {
  // An attacker cycling keys cannot grow the handler's memory: once 1024
  // distinct keys were refused it forgets them all, so a key seen before
  // is logged again as refused once. Spoken to the handler as ZeroMQ does
  // (ZAP over inproc), with the log (stderr) read back.
  test::TempDir dir;
  writePair(dir, "server");
  const CurveKeyPair listed = writePair(dir, "listed");
  zmq::context_t context;
  auto curve = CurveServer::start(context, dir.file("server.key_secret"), dir.file("listed.key"));
  REQUIRE(curve);
  zmq::socket_t zap(context, zmq::socket_type::req);
  zap.set(zmq::sockopt::linger, 0);
  zap.set(zmq::sockopt::rcvtimeo, 10000);
  zap.connect("inproc://zeromq.zap.01");
  const auto ask = [&](const std::string& key, const std::string& version = "1.0") {
    const std::vector<std::string> request = {version, "7",     "picksight", "192.0.2.9",
                                              "",      "CURVE", key};
    for (size_t i = 0; i < request.size(); ++i) {
      zap.send(zmq::buffer(request[i]),
               i + 1 < request.size() ? zmq::send_flags::sndmore : zmq::send_flags::none);
    }
    std::vector<std::string> reply;
    zmq::message_t part;
    do {
      REQUIRE(zap.recv(part));
      reply.push_back(part.to_string());
    } while (part.more());
    REQUIRE(reply.size() >= 3);
    return reply[2];
  };
  // A 32-byte key numbered `i` (never the listed one: it is random).
  const auto key = [](uint32_t i) {
    std::string k(32, '\x5a');
    for (int b = 0; b < 4; ++b) k[static_cast<size_t>(b)] = static_cast<char>(i >> (8 * b));
    return k;
  };
  char first_text[kZ85KeyLength + 1];
  const std::string first = key(0);
  zmq_z85_encode(first_text, reinterpret_cast<const uint8_t*>(first.data()), 32);

  const std::string log = dir.file("stderr.log");
  std::fflush(stderr);
  const int saved = ::dup(STDERR_FILENO);
  const int file = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  REQUIRE(saved >= 0);
  REQUIRE(file >= 0);
  ::dup2(file, STDERR_FILENO);
  ::close(file);
  std::vector<std::string> statuses;
  statuses.push_back(ask(first));
  for (uint32_t i = 1; i <= 1024; ++i) statuses.push_back(ask(key(i)));
  statuses.push_back(ask(first));  // the 1025th distinct key emptied the memory
  std::string listed_binary(32, '\0');
  REQUIRE(zmq_z85_decode(reinterpret_cast<uint8_t*>(listed_binary.data()),
                         listed.public_key.c_str()) != nullptr);
  const std::string admitted = ask(listed_binary);
  // A request of another ZAP version is malformed, even for a listed key.
  const std::string other_version = ask(listed_binary, "2.0");
  ::dup2(saved, STDERR_FILENO);
  ::close(saved);

  CHECK(std::count(statuses.begin(), statuses.end(), "400") == 1026);
  CHECK(admitted == "200");
  CHECK(other_version == "500");
  CHECK((*curve)->refused() == 1026);
  std::ifstream in(log);
  int first_logged_once = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.find(first_text) != std::string::npos && line.find("(1 time)") != std::string::npos)
      ++first_logged_once;
  }
  CHECK(first_logged_once == 2);
}
