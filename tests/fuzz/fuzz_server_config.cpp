// libFuzzer target: parseServerConfig (server/core/server_config.hpp) on arbitrary TOML
// text. Properties: nothing crashes, throws or reads out of bounds; a rejection names the
// source; an accepted config holds only values inside the ranges the parser documents,
// and its [[prop]] entries are finite and inside the world.
//
// Seeds: the built-in config/server.toml (embedded), a generated file setting most keys
// and two props, and tests/fuzz/corpus/server_config.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>
#include <vector>

#include "common/base/embedded.hpp"
#include "server/core/server_config.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;
using fuzz::within;

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  if (const auto builtin = embeddedConfig("server.toml")) {
    seeds.push_back(fuzz::textSeed("builtin_server.toml", *builtin));
  }
  seeds.push_back(fuzz::textSeed(
      "gen_most_keys.toml",
      "[network]\nbind = \"127.0.0.1\"\nport = 0\nio_threads = 3\n"
      "[session]\ntick_rate_hz = 30\nmember_timeout_s = 5.0\njoin_timeout_s = 2.5\n"
      "forward_interval_s = 0.001\nstats_interval_s = 0\n"
      "[limits]\nmax_rooms = 4\nmax_members = 40\nmax_members_per_room = 10\n"
      "max_frame_bytes = 65536\nmax_avatar_bytes = 1048576\navatar_chunk_bytes = 4096\n"
      "upload_stall_timeout_s = 3.0\ncontrol_rate_hz = 50\ncontrol_burst = 20\n"
      "max_primitives_per_avatar = 32\nmax_primitive_extent_m = 1.5\n"
      "upload_min_rate_bytes_per_s = 1024\nupload_rate_window_s = 2\nupload_grace_s = 1\n"
      "upload_deadline_base_s = 10\nupload_deadline_rate_bytes_per_s = 4096\n"
      "max_connections = 100\nmax_connections_per_address = 4\nmax_rooms_per_address = 2\n"
      "limit_loopback = true\n"
      "[room]\nseat_radius_m = 2.0\nseat_spacing_m = 1.0\nring_gap_m = 1.5\n"
      "near_members = 8\nfar_rate_divisor = 2\n"
      "[world]\ngravity_mps2 = 9.0\nfloor_height_m = 0.0\nextent_m = 10\n"
      "max_interaction_datagrams = 2\nsend_self_contact = true\n"
      "contact_window_s = 0.2\ncontact_lead_s = 0.0\n"
      "[props]\nmax_per_room = 4\nspawn_interval_s = 1.0\nspawn_height_m = 0.5\n"
      "[log]\nlevel = \"warn\"\n"
      "[auth]\nsecret_file = \"/etc/vistel/secret\"\n"
      "[tls]\ncert_file = \"server.pem\"\nkey_file = \"server.key\"\n"
      "[[prop]]\nposition = [0.0, 1.0, 0.5]\nradius = 0.2\nmass = 1.5\n"
      "[[prop]]\nkind = \"ball\"\nposition = [1.0, 2.0, 0.0]\nvelocity = [0.0, 0.0, -1.0]\n"));
  seeds.push_back(fuzz::textSeed("gen_empty.toml", ""));
  for (const fuzz::Seed& seed : seeds) {
    const auto parsed = server::parseServerConfig(fuzz::textOf(seed), seed.name);
    check(parsed.ok(), "a seed config parses");
  }
  return seeds;
}

bool finite(const glm::vec3& v) {
  return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z);
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const Result<server::ServerConfig> config = server::parseServerConfig(text, "fuzz.toml");
  if (!config.ok()) {
    fuzz::checkRejection(config.error().message);
    return 0;
  }
  const server::ServerConfig& c = *config;
  check(c.io_threads >= 1 && c.io_threads <= 64, "[network] io_threads in range");
  check(within(c.tick_rate_hz, 1, 240) && within(c.member_timeout_s, 0.1, 3600) &&
            within(c.join_timeout_s, 0.1, 3600) && within(c.forward_interval_s, 0, 0.1) &&
            within(c.stats_interval_s, 0, 86400),
        "[session] values in range");
  check(c.max_rooms >= 1 && c.max_rooms <= 65535 && c.max_members >= 1 && c.max_members <= 65535 &&
            c.max_members_per_room >= 1 && c.max_members_per_room <= 255,
        "[limits] counts in range");
  check(c.max_frame_bytes >= 1024 && c.max_avatar_bytes >= 1024 && c.avatar_chunk_bytes >= 256 &&
            c.avatar_chunk_bytes <= (512u << 10) && c.control_burst >= 1 &&
            within(c.control_rate_hz, 0.1, 100000) && within(c.upload_stall_timeout_s, 0.1, 3600),
        "[limits] sizes and rates in range");
  check(within(c.seat_layout.first_radius_m, 0.1, 100) &&
            within(c.seat_layout.spacing_m, 0.1, 100) &&
            within(c.seat_layout.ring_gap_m, 0.1, 100) && c.interest_near_members >= 1 &&
            c.interest_max_rate_divisor >= 1 && c.interest_max_rate_divisor <= 16,
        "[room] values in range");
  check(within(c.gravity_mps2, 0, 100) && within(c.floor_height_m, -2, 2) &&
            within(c.world_extent_m, 1, 30) && c.max_interaction_datagrams >= 1 &&
            c.max_interaction_datagrams <= 32 && within(c.contact_window_s, 0, 0.5) &&
            within(c.contact_lead_s, 0, 0.5),
        "[world] values in range");
  check(c.max_props_per_room >= 0 && c.max_props_per_room <= 32 &&
            within(c.spawn_interval_s, 0, 3600) && within(c.spawn_height_m, 0, 10),
        "[props] values in range");
  check(server::validatePropSpec(c.spawn_ball).ok(), "[props] ball validates");
  check(static_cast<int>(c.room_props.size()) <= c.max_props_per_room, "[[prop]] count");
  for (const server::RoomPropConfig& p : c.room_props) {
    check(finite(p.position) && finite(p.velocity), "[[prop]] finite position and velocity");
    check(server::validatePropSpec(p.spec).ok(), "[[prop]] ball validates");
  }
  return 0;
}
