#include "common/wire/datagram_crypto.hpp"

#include <cstring>
#include <memory>

#include <openssl/core_names.h>
#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <openssl/hmac.h>
#include <openssl/kdf.h>
#include <openssl/params.h>

namespace vistel::wire {
namespace {

constexpr std::string_view kSalt = "vistel udp v4";
constexpr std::string_view kKeysLabel = "vistel udp v4 keys";
constexpr std::string_view kResumeLabel = "vistel resume";

struct CipherCtxDeleter {
  void operator()(EVP_CIPHER_CTX* c) const { EVP_CIPHER_CTX_free(c); }
};
using CipherCtx = std::unique_ptr<EVP_CIPHER_CTX, CipherCtxDeleter>;

// One context per thread and direction, its cipher set once (key and nonce per call).
EVP_CIPHER_CTX* cipherContext(bool encrypt) {
  thread_local CipherCtx enc, dec;
  CipherCtx& c = encrypt ? enc : dec;
  if (!c) {
    c.reset(EVP_CIPHER_CTX_new());
    if (!c) return nullptr;
    const int ok =
        encrypt ? EVP_EncryptInit_ex(c.get(), EVP_chacha20_poly1305(), nullptr, nullptr, nullptr)
                : EVP_DecryptInit_ex(c.get(), EVP_chacha20_poly1305(), nullptr, nullptr, nullptr);
    if (ok != 1) {
      c.reset();
      return nullptr;
    }
  }
  return c.get();
}

std::array<std::uint8_t, 12> nonceOf(std::uint64_t counter) {
  std::array<std::uint8_t, 12> nonce{};
  for (int i = 0; i < 8; ++i) nonce[4 + i] = static_cast<std::uint8_t>(counter >> (8 * i));
  return nonce;
}

void storeCounter(std::uint64_t counter, std::uint8_t* at) {
  for (int i = 0; i < 8; ++i) at[i] = static_cast<std::uint8_t>(counter >> (8 * i));
}

std::uint64_t loadCounter(const std::uint8_t* at) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = (v << 8) | at[i];
  return v;
}

void appendU32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

}  // namespace

// ---------------------------------------------------------------- key exchange

Result<KeyExchange> KeyExchange::adopt(void* key) {
  KeyExchange k;
  k.key_ = key;  // owned from here (freed with k on failure too)
  std::size_t length = k.public_.size();
  if (EVP_PKEY_get_raw_public_key(static_cast<EVP_PKEY*>(key), k.public_.data(), &length) != 1 ||
      length != k.public_.size()) {
    return fail("X25519 public key unavailable");
  }
  return k;
}

Result<KeyExchange> KeyExchange::generate() {
  EVP_PKEY* key = EVP_PKEY_Q_keygen(nullptr, nullptr, "X25519");
  if (key == nullptr) return fail("X25519 key generation failed");
  return adopt(key);
}

Result<KeyExchange> KeyExchange::fromPrivateKey(std::span<const std::uint8_t> private_key) {
  if (private_key.size() != kX25519KeyBytes) {
    return fail("X25519 private key of {} bytes (expected {})", private_key.size(),
                kX25519KeyBytes);
  }
  EVP_PKEY* key = EVP_PKEY_new_raw_private_key(EVP_PKEY_X25519, nullptr, private_key.data(),
                                               private_key.size());
  if (key == nullptr) return fail("X25519 private key rejected");
  return adopt(key);
}

KeyExchange::KeyExchange(KeyExchange&& other) noexcept : key_(other.key_), public_(other.public_) {
  other.key_ = nullptr;
}

KeyExchange& KeyExchange::operator=(KeyExchange&& other) noexcept {
  if (this != &other) {
    EVP_PKEY_free(static_cast<EVP_PKEY*>(key_));
    key_ = other.key_;
    public_ = other.public_;
    other.key_ = nullptr;
  }
  return *this;
}

KeyExchange::~KeyExchange() { EVP_PKEY_free(static_cast<EVP_PKEY*>(key_)); }

Result<std::array<std::uint8_t, 32>> KeyExchange::sharedSecret(
    std::span<const std::uint8_t> peer) const {
  if (peer.size() != kX25519KeyBytes) {
    return fail("X25519 public key of {} bytes (expected {})", peer.size(), kX25519KeyBytes);
  }
  if (key_ == nullptr) return fail("X25519 key pair moved from");
  std::unique_ptr<EVP_PKEY, decltype(&EVP_PKEY_free)> peer_key(
      EVP_PKEY_new_raw_public_key(EVP_PKEY_X25519, nullptr, peer.data(), peer.size()),
      &EVP_PKEY_free);
  if (!peer_key) return fail("X25519 public key rejected");
  std::unique_ptr<EVP_PKEY_CTX, decltype(&EVP_PKEY_CTX_free)> ctx(
      EVP_PKEY_CTX_new(static_cast<EVP_PKEY*>(key_), nullptr), &EVP_PKEY_CTX_free);
  std::array<std::uint8_t, 32> secret{};
  std::size_t length = secret.size();
  // OpenSSL refuses (derive fails) when the result is all zero: a low-order peer point.
  if (!ctx || EVP_PKEY_derive_init(ctx.get()) != 1 ||
      EVP_PKEY_derive_set_peer(ctx.get(), peer_key.get()) != 1 ||
      EVP_PKEY_derive(ctx.get(), secret.data(), &length) != 1 || length != secret.size()) {
    return fail("X25519 key agreement failed (bad peer public key)");
  }
  std::uint8_t any = 0;
  for (std::uint8_t b : secret) any |= b;
  if (any == 0) return fail("X25519 key agreement gave an all-zero secret");
  return secret;
}

Result<SessionKeys> deriveSessionKeys(std::span<const std::uint8_t> shared_secret,
                                      const PublicKey& client_public,
                                      const PublicKey& server_public, std::uint32_t member_id,
                                      std::string_view room) {
  // info = label || client public || server public || u32 member id || room name.
  std::vector<std::uint8_t> info(kKeysLabel.begin(), kKeysLabel.end());
  info.insert(info.end(), client_public.begin(), client_public.end());
  info.insert(info.end(), server_public.begin(), server_public.end());
  appendU32(info, member_id);
  info.insert(info.end(), room.begin(), room.end());

  std::unique_ptr<EVP_KDF, decltype(&EVP_KDF_free)> kdf(EVP_KDF_fetch(nullptr, "HKDF", nullptr),
                                                        &EVP_KDF_free);
  if (!kdf) return fail("HKDF unavailable");
  std::unique_ptr<EVP_KDF_CTX, decltype(&EVP_KDF_CTX_free)> ctx(EVP_KDF_CTX_new(kdf.get()),
                                                                &EVP_KDF_CTX_free);
  if (!ctx) return fail("HKDF context failed");
  char digest[] = "SHA256";
  OSSL_PARAM params[] = {
      OSSL_PARAM_construct_utf8_string(OSSL_KDF_PARAM_DIGEST, digest, 0),
      OSSL_PARAM_construct_octet_string(OSSL_KDF_PARAM_KEY,
                                        const_cast<std::uint8_t*>(shared_secret.data()),
                                        shared_secret.size()),
      OSSL_PARAM_construct_octet_string(OSSL_KDF_PARAM_SALT, const_cast<char*>(kSalt.data()),
                                        kSalt.size()),
      OSSL_PARAM_construct_octet_string(OSSL_KDF_PARAM_INFO, info.data(), info.size()),
      OSSL_PARAM_construct_end()};
  std::array<std::uint8_t, 4 * kAeadKeyBytes> okm{};
  if (EVP_KDF_derive(ctx.get(), okm.data(), okm.size(), params) != 1) {
    return fail("HKDF derivation failed");
  }
  SessionKeys keys;
  std::memcpy(keys.client_to_server.data(), okm.data(), kAeadKeyBytes);
  std::memcpy(keys.server_to_client.data(), okm.data() + kAeadKeyBytes, kAeadKeyBytes);
  std::memcpy(keys.server_hello.data(), okm.data() + 2 * kAeadKeyBytes, kAeadKeyBytes);
  std::memcpy(keys.resume.data(), okm.data() + 3 * kAeadKeyBytes, kResumeSecretBytes);
  OPENSSL_cleanse(okm.data(), okm.size());
  return keys;
}

Result<Handshake> serverHandshake(std::span<const std::uint8_t> client_public,
                                  std::uint32_t member_id, std::string_view room) {
  if (client_public.size() != kX25519KeyBytes) {
    return fail("X25519 public key of {} bytes (expected {})", client_public.size(),
                kX25519KeyBytes);
  }
  auto pair = KeyExchange::generate();
  if (!pair) return pair.error();
  auto secret = pair->sharedSecret(client_public);
  if (!secret) return secret.error();
  PublicKey client{};
  std::memcpy(client.data(), client_public.data(), client.size());
  Handshake h;
  h.server_public = pair->publicKey();
  auto keys = deriveSessionKeys(*secret, client, h.server_public, member_id, room);
  OPENSSL_cleanse(secret->data(), secret->size());
  if (!keys) return keys.error();
  h.keys = *keys;
  return h;
}

ResumeProof resumeProof(const ResumeSecret& secret, std::span<const std::uint8_t> new_public) {
  std::vector<std::uint8_t> message(kResumeLabel.begin(), kResumeLabel.end());
  message.insert(message.end(), new_public.begin(), new_public.end());
  ResumeProof proof{};
  unsigned int length = 0;
  HMAC(EVP_sha256(), secret.data(), static_cast<int>(secret.size()), message.data(), message.size(),
       proof.data(), &length);
  return proof;
}

bool resumeProofMatches(const ResumeSecret& secret, std::span<const std::uint8_t> new_public,
                        std::span<const std::uint8_t> proof) {
  if (proof.size() != kResumeProofBytes) return false;
  const ResumeProof expected = resumeProof(secret, new_public);
  return CRYPTO_memcmp(expected.data(), proof.data(), expected.size()) == 0;
}

// ---------------------------------------------------------------- AEAD

bool sealDatagram(const AeadKey& key, std::uint64_t counter, std::size_t clear_bytes,
                  std::vector<std::uint8_t>& datagram) {
  if (counter == 0 || clear_bytes < kCounterBytes || datagram.size() < clear_bytes) return false;
  EVP_CIPHER_CTX* ctx = cipherContext(true);
  if (ctx == nullptr) return false;
  storeCounter(counter, datagram.data() + clear_bytes - kCounterBytes);
  const auto nonce = nonceOf(counter);
  const std::size_t body = datagram.size() - clear_bytes;
  int length = 0;
  if (EVP_EncryptInit_ex(ctx, nullptr, nullptr, key.data(), nonce.data()) != 1 ||
      EVP_EncryptUpdate(ctx, nullptr, &length, datagram.data(), static_cast<int>(clear_bytes)) !=
          1) {
    return false;
  }
  if (body > 0 && EVP_EncryptUpdate(ctx, datagram.data() + clear_bytes, &length,
                                    datagram.data() + clear_bytes, static_cast<int>(body)) != 1) {
    return false;
  }
  std::array<std::uint8_t, kAeadTagBytes> tag{};
  if (EVP_EncryptFinal_ex(ctx, tag.data(), &length) != 1 ||
      EVP_CIPHER_CTX_ctrl(ctx, EVP_CTRL_AEAD_GET_TAG, static_cast<int>(tag.size()), tag.data()) !=
          1) {
    return false;
  }
  datagram.insert(datagram.end(), tag.begin(), tag.end());
  return true;
}

bool openDatagram(const AeadKey& key, std::size_t clear_bytes, std::span<std::uint8_t> datagram,
                  std::uint64_t& counter, std::size_t& plain_size) {
  if (clear_bytes < kCounterBytes || datagram.size() < clear_bytes + kAeadTagBytes) return false;
  EVP_CIPHER_CTX* ctx = cipherContext(false);
  if (ctx == nullptr) return false;
  counter = loadCounter(datagram.data() + clear_bytes - kCounterBytes);
  const auto nonce = nonceOf(counter);
  const std::size_t body = datagram.size() - clear_bytes - kAeadTagBytes;
  std::uint8_t* tag = datagram.data() + clear_bytes + body;
  int length = 0;
  if (EVP_DecryptInit_ex(ctx, nullptr, nullptr, key.data(), nonce.data()) != 1 ||
      EVP_DecryptUpdate(ctx, nullptr, &length, datagram.data(), static_cast<int>(clear_bytes)) !=
          1) {
    return false;
  }
  if (body > 0 && EVP_DecryptUpdate(ctx, datagram.data() + clear_bytes, &length,
                                    datagram.data() + clear_bytes, static_cast<int>(body)) != 1) {
    return false;
  }
  if (EVP_CIPHER_CTX_ctrl(ctx, EVP_CTRL_AEAD_SET_TAG, static_cast<int>(kAeadTagBytes), tag) != 1 ||
      EVP_DecryptFinal_ex(ctx, tag, &length) != 1) {
    return false;
  }
  plain_size = clear_bytes + body;
  return true;
}

std::uint64_t peekCounter(std::span<const std::uint8_t> datagram, std::size_t clear_bytes) {
  if (clear_bytes < kCounterBytes || datagram.size() < clear_bytes) return 0;
  return loadCounter(datagram.data() + clear_bytes - kCounterBytes);
}

// ---------------------------------------------------------------- replay window

ReplayWindow::Verdict ReplayWindow::check(std::uint64_t counter) const {
  if (counter == 0) return Verdict::kInvalid;
  if (counter > newest_) return Verdict::kFresh;
  const std::uint64_t behind = newest_ - counter;
  if (behind >= kSize) return Verdict::kTooOld;
  return ((seen_ >> behind) & 1u) != 0 ? Verdict::kDuplicate : Verdict::kFresh;
}

void ReplayWindow::accept(std::uint64_t counter) {
  if (counter == 0) return;
  if (counter > newest_) {
    const std::uint64_t ahead = counter - newest_;
    seen_ = ahead >= kSize ? 0 : seen_ << ahead;
    seen_ |= 1u;
    newest_ = counter;
    return;
  }
  const std::uint64_t behind = newest_ - counter;
  if (behind < kSize) seen_ |= std::uint64_t{1} << behind;
}

std::string_view replayReason(ReplayWindow::Verdict verdict) {
  switch (verdict) {
    case ReplayWindow::Verdict::kFresh:
      return {};
    case ReplayWindow::Verdict::kDuplicate:
      return "replayed datagram";
    case ReplayWindow::Verdict::kTooOld:
      return "datagram too old";
    case ReplayWindow::Verdict::kInvalid:
      return "invalid counter";
  }
  return "invalid counter";
}

bool DatagramOpener::open(std::size_t clear_bytes, std::span<std::uint8_t> datagram,
                          std::size_t& plain_size, std::string_view& reason) {
  const auto verdict = window.check(peekCounter(datagram, clear_bytes));
  if (verdict != ReplayWindow::Verdict::kFresh) {
    reason = replayReason(verdict);
    return false;
  }
  std::uint64_t counter = 0;
  if (!openDatagram(key, clear_bytes, datagram, counter, plain_size)) {
    reason = "bad datagram tag";
    return false;
  }
  window.accept(counter);
  return true;
}

}  // namespace vistel::wire
