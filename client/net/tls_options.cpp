#include "client/net/tls_options.hpp"

#include <CLI/CLI.hpp>

namespace vistel::net {

void addTlsOptions(CLI::App& app, tls::ClientTlsSettings& settings) {
  app.add_flag("--tls", settings.enabled,
               "the control channel over TLS (a server started with --tls-cert)");
  app.add_option("--tls-ca", settings.ca_file,
                 "with --tls: trust the server's certificate if this CA file (PEM) signed it "
                 "(default: the system's CAs)");
  app.add_option("--tls-pin", settings.pin_sha256,
                 "with --tls: trust only the certificate with this SHA-256 (64 hex digits of its "
                 "DER form)");
}

std::string checkTlsOptions(const tls::ClientTlsSettings& settings) {
  if (!settings.enabled && (!settings.ca_file.empty() || !settings.pin_sha256.empty())) {
    return "--tls-ca and --tls-pin need --tls";
  }
  if (settings.enabled) {
    if (auto context = tls::makeClientContext(settings); !context) return context.error().message;
  }
  return {};
}

}  // namespace vistel::net
