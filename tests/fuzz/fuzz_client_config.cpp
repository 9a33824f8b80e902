// libFuzzer target: parseClientConfig (client/net/client_config.hpp) on arbitrary TOML text.
// Properties: nothing crashes, throws or reads out of bounds (toml++ exceptions stay
// inside); a rejection names the source; an accepted config holds only values inside the
// ranges the parser documents (every key is optional, so the defaults must be inside too).
//
// Seeds: the built-in config/client.toml (embedded), a generated file setting every key,
// and tests/fuzz/corpus/client_config.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "client/net/client_config.hpp"
#include "common/base/embedded.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;
using fuzz::within;

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  if (const auto builtin = embeddedConfig("client.toml")) {
    seeds.push_back(fuzz::textSeed("builtin_client.toml", *builtin));
  }
  seeds.push_back(fuzz::textSeed("gen_every_key.toml",
                                 "[network]\nhello_interval_s = 0.2\nhello_timeout_s = 4.0\n"
                                 "join_timeout_s = 12\nping_interval_s = 0.5\n"
                                 "server_timeout_s = 20.0\n"
                                 "[playback]\ninterpolation_delay_s = 0.15\njitter_capacity = 64\n"
                                 "[source]\nidle_rate_hz = 60\n"
                                 "[avatars]\ncache_dir = \"/tmp/vistel-fuzz-cache\"\n"
                                 "[view]\nwidth = 640\nheight = 480\nworker_threads = 3\n"
                                 "frame_rate_hz = 90.0\ngpu_skinning = false\n"
                                 "[deform]\nenabled = true\nserver_interactions = false\n"
                                 "[lod]\nenabled = true\nfull_radius_m = 3.0\n"
                                 "reduced_radius_m = 8.0\nhysteresis_m = 0.5\nreduced_every = 3\n"
                                 "max_full = 4\nmax_reduced = 12\ncontact_full = true\n"));
  seeds.push_back(fuzz::textSeed("gen_empty.toml", ""));
  for (const fuzz::Seed& seed : seeds) {
    const auto parsed = net::parseClientConfig(fuzz::textOf(seed), seed.name);
    check(parsed.ok(), "a seed config parses");
  }
  return seeds;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const Result<net::ClientConfig> config = net::parseClientConfig(text, "fuzz.toml");
  if (!config.ok()) {
    fuzz::checkRejection(config.error().message);
    return 0;
  }
  const net::SessionSettings& s = config->session;
  check(within(s.hello_interval_s, 0.01, 10) && within(s.hello_timeout_s, 0.1, 600) &&
            within(s.join_timeout_s, 0.1, 600) && within(s.ping_interval_s, 0.01, 60) &&
            within(s.server_timeout_s, 0.5, 3600),
        "[network] values in range");
  check(within(config->interpolation_delay_s, 0, 5) && s.jitter_capacity >= 2 &&
            s.jitter_capacity <= 1024,
        "[playback] values in range");
  check(within(config->idle_rate_hz, 1, 240), "[source] idle_rate_hz in range");
  check(config->width >= 16 && config->width <= 8192 && config->height >= 16 &&
            config->height <= 8192 && config->worker_threads >= 1 && config->worker_threads <= 64 &&
            within(config->frame_rate_hz, 1, 1000),
        "[view] values in range");
  const DeformLodSettings& lod = config->lod;
  check(validateDeformLodSettings(lod).ok(), "[lod] validates");
  check(within(lod.full_radius_m, 0, 1000) && within(lod.reduced_radius_m, 0, 1000) &&
            within(lod.hysteresis_m, 0, 100) && lod.reduced_every >= 1 && lod.reduced_every <= 60,
        "[lod] values in range");
  return 0;
}
