// Sealed frames: XChaCha20-Poly1305 from libsodium, one seal per frame.
#include "picksight/transport/frame_seal.hpp"

#include <sodium.h>

#include <cstring>
#include <stdexcept>

#include "picksight/transport/frame_message.hpp"

namespace picksight::transport {
namespace {

constexpr char kMagic[4] = {'P', 'S', 'F', '1'};
constexpr size_t kNonceBytes = crypto_aead_xchacha20poly1305_ietf_NPUBBYTES;
// Part 2's clear prefix: magic, key id, nonce.
constexpr size_t kPrefixBytes = sizeof(kMagic) + 8 + kNonceBytes;
static_assert(kNonceBytes == 24 && crypto_aead_xchacha20poly1305_ietf_ABYTES == kSealTag);
static_assert(kSealedHeaderOverhead == kPrefixBytes + kSealTag);

void needSodium() {
  // sodium_init is safe to call again and from any thread; it fails only
  // when the system has no source of randomness.
  static const int ready = sodium_init();
  if (ready < 0) throw std::runtime_error("libsodium: cannot initialise (no randomness?)");
}

// Both parts' associated data: the topic, then part 2's clear prefix.
std::string associatedData(const void* topic, size_t topic_size, const unsigned char* prefix) {
  std::string ad(static_cast<const char*>(topic), topic_size);
  ad.append(reinterpret_cast<const char*>(prefix), kPrefixBytes);
  return ad;
}

const unsigned char* bytesOf(const std::string& s) {
  return reinterpret_cast<const unsigned char*>(s.data());
}

}  // namespace

FrameKey newFrameKey() {
  needSodium();
  FrameKey k;
  crypto_aead_xchacha20poly1305_ietf_keygen(k.key.data());
  randombytes_buf(&k.id, sizeof(k.id));
  return k;
}

void sendSealedFrame(zmq::socket_t& socket, const Frame& frame, const FrameKey& key) {
  needSodium();
  // As sendFrame: the payload is rows of `stride` bytes, the last included.
  Frame dense = frame;
  if (!dense.image.isContinuous()) dense.image = frame.image.clone();
  const std::string header = frameHeaderOf(dense).SerializeAsString();
  const size_t pixel_bytes = dense.image.total() * dense.image.elemSize();

  zmq::message_t envelope(kPrefixBytes + header.size() + kSealTag);
  auto* prefix = static_cast<unsigned char*>(envelope.data());
  std::memcpy(prefix, kMagic, sizeof(kMagic));
  for (int i = 0; i < 8; ++i) prefix[4 + i] = static_cast<unsigned char>(key.id >> (8 * i));
  unsigned char* nonce = prefix + 12;
  randombytes_buf(nonce, kNonceBytes);
  const std::string ad = associatedData(frame.info.camera.data(), frame.info.camera.size(), prefix);
  unsigned long long written = 0;
  crypto_aead_xchacha20poly1305_ietf_encrypt(prefix + kPrefixBytes, &written, bytesOf(header),
                                             header.size(), bytesOf(ad), ad.size(), nullptr,
                                             nonce, key.key.data());
  // The pixels under the next nonce: one key never seals two messages
  // under one nonce.
  unsigned char pixel_nonce[kNonceBytes];
  std::memcpy(pixel_nonce, nonce, kNonceBytes);
  sodium_increment(pixel_nonce, kNonceBytes);
  zmq::message_t pixels(pixel_bytes + kSealTag);
  crypto_aead_xchacha20poly1305_ietf_encrypt(static_cast<unsigned char*>(pixels.data()), &written,
                                             dense.image.data, pixel_bytes, bytesOf(ad), ad.size(),
                                             nullptr, pixel_nonce, key.key.data());
  // PUB never blocks: a subscriber whose pipe is full misses the message.
  socket.send(zmq::buffer(frame.info.camera), zmq::send_flags::sndmore);
  socket.send(envelope, zmq::send_flags::sndmore);
  socket.send(pixels, zmq::send_flags::none);
}

std::optional<uint64_t> sealedKeyId(const zmq::message_t& envelope) {
  if (envelope.size() < kSealedHeaderOverhead) return std::nullopt;
  const auto* p = static_cast<const unsigned char*>(envelope.data());
  if (std::memcmp(p, kMagic, sizeof(kMagic)) != 0) return std::nullopt;
  uint64_t id = 0;
  for (int i = 0; i < 8; ++i) id |= static_cast<uint64_t>(p[4 + i]) << (8 * i);
  return id;
}

std::optional<OpenedFrame> openSealedFrame(const zmq::message_t& topic,
                                           const zmq::message_t& envelope,
                                           const zmq::message_t& pixels, const FrameKey& key) {
  needSodium();
  const std::optional<uint64_t> id = sealedKeyId(envelope);
  if (!id || *id != key.id || pixels.size() < kSealTag) return std::nullopt;
  const auto* prefix = static_cast<const unsigned char*>(envelope.data());
  const unsigned char* nonce = prefix + 12;
  const std::string ad = associatedData(topic.data(), topic.size(), prefix);
  OpenedFrame out;
  out.header.resize(envelope.size() - kSealedHeaderOverhead);
  unsigned long long opened = 0;
  if (crypto_aead_xchacha20poly1305_ietf_decrypt(
          reinterpret_cast<unsigned char*>(out.header.data()), &opened, nullptr,
          prefix + kPrefixBytes, envelope.size() - kPrefixBytes, bytesOf(ad), ad.size(), nonce,
          key.key.data()) != 0) {
    return std::nullopt;
  }
  unsigned char pixel_nonce[kNonceBytes];
  std::memcpy(pixel_nonce, nonce, kNonceBytes);
  sodium_increment(pixel_nonce, kNonceBytes);
  out.pixels.rebuild(pixels.size() - kSealTag);
  if (crypto_aead_xchacha20poly1305_ietf_decrypt(
          static_cast<unsigned char*>(out.pixels.data()), &opened, nullptr,
          static_cast<const unsigned char*>(pixels.data()), pixels.size(), bytesOf(ad), ad.size(),
          pixel_nonce, key.key.data()) != 0) {
    return std::nullopt;
  }
  return out;
}

}  // namespace picksight::transport
