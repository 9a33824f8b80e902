// TLS contexts for the control channel (TLS 1.2 or later).
//
// Server: a certificate chain and its private key (PEM files). Client: verify the server
// against a CA file (and the host name it connects to), or against one pinned
// certificate: the SHA-256 of its DER encoding, 64 hex digits (certificateFingerprint, or
// `openssl x509 -in cert.pem -outform DER | sha256sum`), which skips CA and name checks;
// with neither, against the system's CAs. Errors name the file or say what is wrong.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "common/base/result.hpp"
#include "common/tls/control_stream.hpp"

namespace vistel::tls {

struct ClientTlsSettings {
  bool enabled = false;    // --tls
  std::string ca_file;     // --tls-ca: PEM CA certificates (empty: the system's)
  std::string pin_sha256;  // --tls-pin: 64 hex digits (empty: no pin)
};

Result<std::unique_ptr<asio::ssl::context>> makeServerContext(const std::string& cert_file,
                                                              const std::string& key_file);
Result<std::unique_ptr<asio::ssl::context>> makeClientContext(const ClientTlsSettings& settings);

// Before a client handshake: SNI and the host name check (CA mode), or the pin check.
// When the pin does not match, *note says so (the server's fingerprint and the pin) for
// the caller's error message.
Status prepareClientStream(ControlStream& stream, const ClientTlsSettings& settings,
                           const std::string& host, std::shared_ptr<std::string> note);

// SHA-256 of a PEM certificate file's first certificate (DER), 64 lowercase hex digits.
Result<std::string> certificateFingerprint(const std::string& cert_file);

// The OpenSSL reason of a failed handshake, made readable ("certificate verify failed:
// certificate pin mismatch").
std::string describeTlsError(const boost::system::error_code& ec);

}  // namespace vistel::tls
