#include "common/tls/tls_context.hpp"

#include <openssl/err.h>
#include <openssl/evp.h>
#include <openssl/pem.h>
#include <openssl/ssl.h>
#include <openssl/x509.h>

#include <cstdio>

namespace vistel::tls {
namespace {

std::string hex(const unsigned char* bytes, unsigned int n) {
  static const char* kDigits = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < n; ++i) {
    out.push_back(kDigits[bytes[i] >> 4]);
    out.push_back(kDigits[bytes[i] & 15]);
  }
  return out;
}

std::string fingerprintOf(X509* cert) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int n = 0;
  if (X509_digest(cert, EVP_sha256(), digest, &n) != 1) return {};
  return hex(digest, n);
}

bool isPin(const std::string& pin) {
  if (pin.size() != 64) return false;
  for (char c : pin) {
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  }
  return true;
}

std::string lowercase(std::string s) {
  for (char& c : s) {
    if (c >= 'A' && c <= 'F') c = static_cast<char>(c - 'A' + 'a');
  }
  return s;
}

}  // namespace

Result<std::unique_ptr<asio::ssl::context>> makeServerContext(const std::string& cert_file,
                                                              const std::string& key_file) {
  auto context = std::make_unique<asio::ssl::context>(asio::ssl::context::tls_server);
  SSL_CTX_set_min_proto_version(context->native_handle(), TLS1_2_VERSION);
  boost::system::error_code ec;
  context->use_certificate_chain_file(cert_file, ec);
  if (ec) return fail("--tls-cert {}: {}", cert_file, ec.message());
  context->use_private_key_file(key_file, asio::ssl::context::pem, ec);
  if (ec) return fail("--tls-key {}: {} (is it the key of {}?)", key_file, ec.message(), cert_file);
  if (SSL_CTX_check_private_key(context->native_handle()) != 1) {
    return fail("--tls-key {} does not belong to the certificate in {}", key_file, cert_file);
  }
  return context;
}

Result<std::unique_ptr<asio::ssl::context>> makeClientContext(const ClientTlsSettings& settings) {
  auto context = std::make_unique<asio::ssl::context>(asio::ssl::context::tls_client);
  SSL_CTX_set_min_proto_version(context->native_handle(), TLS1_2_VERSION);
  boost::system::error_code ec;
  if (!settings.pin_sha256.empty()) {
    if (!isPin(lowercase(settings.pin_sha256))) {
      return fail("--tls-pin '{}': expected 64 hex digits (the SHA-256 of the certificate)",
                  settings.pin_sha256);
    }
  } else if (!settings.ca_file.empty()) {
    context->load_verify_file(settings.ca_file, ec);
    if (ec) return fail("--tls-ca {}: {}", settings.ca_file, ec.message());
  } else {
    context->set_default_verify_paths(ec);
    if (ec) return fail("TLS: the system's CA certificates: {}", ec.message());
  }
  context->set_verify_mode(asio::ssl::verify_peer);
  return context;
}

Status prepareClientStream(ControlStream& stream, const ClientTlsSettings& settings,
                           const std::string& host, std::shared_ptr<std::string> note) {
  TlsStream& tls = stream.tlsStream();
  // SNI (a host name, not an address).
  boost::system::error_code ec;
  asio::ip::make_address(host, ec);
  if (ec && SSL_set_tlsext_host_name(tls.native_handle(), host.c_str()) != 1) {
    return fail("TLS: cannot set the server name '{}'", host);
  }
  if (!settings.pin_sha256.empty()) {
    // The leaf certificate must be the pinned one; the chain and names are not checked.
    const std::string pin = lowercase(settings.pin_sha256);
    tls.set_verify_callback([pin, note](bool /*preverified*/, asio::ssl::verify_context& ctx) {
      X509_STORE_CTX* store = ctx.native_handle();
      if (X509_STORE_CTX_get_error_depth(store) > 0) return true;
      const std::string got = fingerprintOf(X509_STORE_CTX_get_current_cert(store));
      if (got == pin) return true;
      if (note) *note = "the server's certificate has SHA-256 " + got + ", not the pinned " + pin;
      X509_STORE_CTX_set_error(store, X509_V_ERR_CERT_REJECTED);
      return false;
    });
  } else {
    tls.set_verify_callback(asio::ssl::rfc2818_verification(host));
  }
  return {};
}

Result<std::string> certificateFingerprint(const std::string& cert_file) {
  FILE* f = std::fopen(cert_file.c_str(), "rb");
  if (f == nullptr) return fail("{}: cannot open", cert_file);
  X509* cert = PEM_read_X509(f, nullptr, nullptr, nullptr);
  std::fclose(f);
  if (cert == nullptr) return fail("{}: no PEM certificate", cert_file);
  std::string out = fingerprintOf(cert);
  X509_free(cert);
  return out;
}

std::string describeTlsError(const boost::system::error_code& ec) {
  if (ec.category() == asio::error::get_ssl_category()) {
    const char* reason = ERR_reason_error_string(static_cast<unsigned long>(ec.value()));
    if (reason != nullptr) return reason;
  }
  if (ec == asio::ssl::error::stream_truncated) return "the peer closed during the handshake";
  return ec.message();
}

}  // namespace vistel::tls
