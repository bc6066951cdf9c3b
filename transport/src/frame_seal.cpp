// Sealed frames: ChaCha20-Poly1305 (RFC 8439) from OpenSSL, one seal per
// frame.
#include "picksight/transport/frame_seal.hpp"

#include <openssl/evp.h>
#include <openssl/rand.h>

#include <cstring>
#include <memory>
#include <stdexcept>

#include "picksight/transport/frame_message.hpp"

namespace picksight::transport {
namespace {

constexpr char kMagic[4] = {'P', 'S', 'F', '1'};
constexpr size_t kNonceBytes = 12;
// Part 2's clear prefix: magic, key id, nonce.
constexpr size_t kPrefixBytes = sizeof(kMagic) + 8 + kNonceBytes;
static_assert(kSealedHeaderOverhead == kPrefixBytes + kSealTag);
// OpenSSL's lengths are ints: a part beyond this is refused whole.
constexpr size_t kMaxSealedBytes = 1u << 30;

using CipherContext = std::unique_ptr<EVP_CIPHER_CTX, decltype(&EVP_CIPHER_CTX_free)>;

void randomBytes(void* out, size_t n) {
  if (RAND_bytes(static_cast<unsigned char*>(out), static_cast<int>(n)) != 1)
    throw std::runtime_error("OpenSSL: no random bytes for the frames' key");
}

// The nonce after `nonce`: its 12 bytes as a little-endian number, plus one.
void increment(unsigned char* nonce) {
  for (size_t i = 0; i < kNonceBytes && ++nonce[i] == 0; ++i) {
  }
}

// Seals `n` bytes of `in` into `out` (n + kSealTag bytes), bound to `ad`.
void seal(const FrameKey& key, const unsigned char* nonce, const std::string& ad,
          const unsigned char* in, size_t n, unsigned char* out) {
  if (n > kMaxSealedBytes) throw std::length_error("a frame part too large to seal");
  CipherContext ctx(EVP_CIPHER_CTX_new(), EVP_CIPHER_CTX_free);
  int len = 0;
  int tail = 0;
  if (!ctx ||
      EVP_EncryptInit_ex(ctx.get(), EVP_chacha20_poly1305(), nullptr, key.key.data(), nonce) != 1 ||
      EVP_EncryptUpdate(ctx.get(), nullptr, &len, reinterpret_cast<const unsigned char*>(ad.data()),
                        static_cast<int>(ad.size())) != 1 ||
      EVP_EncryptUpdate(ctx.get(), out, &len, in, static_cast<int>(n)) != 1 ||
      EVP_EncryptFinal_ex(ctx.get(), out + len, &tail) != 1 ||
      EVP_CIPHER_CTX_ctrl(ctx.get(), EVP_CTRL_AEAD_GET_TAG, kSealTag, out + n) != 1) {
    throw std::runtime_error("OpenSSL: sealing a frame failed");
  }
}

// Opens `n` sealed bytes (the tag last) into `out` (n - kSealTag bytes):
// false when they do not open.
bool open(const FrameKey& key, const unsigned char* nonce, const std::string& ad,
          const unsigned char* in, size_t n, unsigned char* out) {
  if (n < kSealTag || n > kMaxSealedBytes + kSealTag) return false;
  const size_t body = n - kSealTag;
  CipherContext ctx(EVP_CIPHER_CTX_new(), EVP_CIPHER_CTX_free);
  int len = 0;
  int tail = 0;
  // The tag is only read by OpenSSL; its API takes it as writable.
  unsigned char tag[kSealTag];
  std::memcpy(tag, in + body, kSealTag);
  return ctx &&
         EVP_DecryptInit_ex(ctx.get(), EVP_chacha20_poly1305(), nullptr, key.key.data(), nonce) ==
             1 &&
         EVP_DecryptUpdate(ctx.get(), nullptr, &len,
                           reinterpret_cast<const unsigned char*>(ad.data()),
                           static_cast<int>(ad.size())) == 1 &&
         EVP_DecryptUpdate(ctx.get(), out, &len, in, static_cast<int>(body)) == 1 &&
         EVP_CIPHER_CTX_ctrl(ctx.get(), EVP_CTRL_AEAD_SET_TAG, kSealTag, tag) == 1 &&
         EVP_DecryptFinal_ex(ctx.get(), out + len, &tail) == 1;
}

// Both parts' associated data: the topic, then part 2's clear prefix.
std::string associatedData(const void* topic, size_t topic_size, const unsigned char* prefix) {
  std::string ad(static_cast<const char*>(topic), topic_size);
  ad.append(reinterpret_cast<const char*>(prefix), kPrefixBytes);
  return ad;
}

}  // namespace

FrameKey newFrameKey() {
  FrameKey k;
  randomBytes(k.key.data(), k.key.size());
  randomBytes(&k.id, sizeof(k.id));
  return k;
}

FrameSealer::FrameSealer(const FrameKey& key) : key_(key) {
  randomBytes(prefix_.data(), prefix_.size());
}

void FrameSealer::send(zmq::socket_t& socket, const Frame& frame) {
  // As sendFrame: the payload is rows of `stride` bytes, the last included.
  Frame dense = frame;
  if (!dense.image.isContinuous()) dense.image = frame.image.clone();
  const std::string header = frameHeaderOf(dense).SerializeAsString();
  const size_t pixel_bytes = dense.image.total() * dense.image.elemSize();

  zmq::message_t envelope(kPrefixBytes + header.size() + kSealTag);
  auto* prefix = static_cast<unsigned char*>(envelope.data());
  std::memcpy(prefix, kMagic, sizeof(kMagic));
  for (int i = 0; i < 8; ++i) prefix[4 + i] = static_cast<unsigned char>(key_.id >> (8 * i));
  // The nonce: the random prefix, then the count (little-endian); the
  // pixels take the next one.
  unsigned char* nonce = prefix + 12;
  const uint64_t count = count_.fetch_add(2);
  std::memcpy(nonce, prefix_.data(), prefix_.size());
  for (int i = 0; i < 8; ++i) nonce[4 + i] = static_cast<unsigned char>(count >> (8 * i));
  const std::string ad = associatedData(frame.info.camera.data(), frame.info.camera.size(), prefix);
  seal(key_, nonce, ad, reinterpret_cast<const unsigned char*>(header.data()), header.size(),
       prefix + kPrefixBytes);
  unsigned char pixel_nonce[kNonceBytes];
  std::memcpy(pixel_nonce, nonce, kNonceBytes);
  increment(pixel_nonce);
  zmq::message_t pixels(pixel_bytes + kSealTag);
  seal(key_, pixel_nonce, ad, dense.image.data, pixel_bytes,
       static_cast<unsigned char*>(pixels.data()));
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

std::optional<std::string> openSealedFrame(const zmq::message_t& topic,
                                           const zmq::message_t& envelope, zmq::message_t& pixels,
                                           const FrameKey& key) {
  const std::optional<uint64_t> id = sealedKeyId(envelope);
  if (!id || *id != key.id || pixels.size() < kSealTag) return std::nullopt;
  const auto* prefix = static_cast<const unsigned char*>(envelope.data());
  const unsigned char* nonce = prefix + 12;
  const std::string ad = associatedData(topic.data(), topic.size(), prefix);
  std::string header(envelope.size() - kSealedHeaderOverhead, '\0');
  if (!open(key, nonce, ad, prefix + kPrefixBytes, envelope.size() - kPrefixBytes,
            reinterpret_cast<unsigned char*>(header.data()))) {
    return std::nullopt;
  }
  unsigned char pixel_nonce[kNonceBytes];
  std::memcpy(pixel_nonce, nonce, kNonceBytes);
  increment(pixel_nonce);
  // In place (OpenSSL allows the output on its input, exactly): a second
  // buffer of a frame's size cost each subscriber an allocation and its
  // page faults per frame.
  auto* bytes = static_cast<unsigned char*>(pixels.data());
  if (!open(key, pixel_nonce, ad, bytes, pixels.size(), bytes)) return std::nullopt;
  return header;
}

}  // namespace picksight::transport
