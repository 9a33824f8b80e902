// The control channel's TLS options that vistel-client and vistel-bot share: --tls,
// --tls-ca and --tls-pin (common/tls/tls_context.hpp), registered and checked alike.
#pragma once

#include <string>

#include "common/tls/tls_context.hpp"

namespace CLI {
class App;
}

namespace vistel::net {

void addTlsOptions(CLI::App& app, tls::ClientTlsSettings& settings);

// After parsing: --tls-ca and --tls-pin need --tls, and with --tls the context must load
// (a CA file that reads, a pin of 64 hex digits). Empty when fine, else what to tell the user.
std::string checkTlsOptions(const tls::ClientTlsSettings& settings);

}  // namespace vistel::net
