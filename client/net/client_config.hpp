// Settings of the site client and the bots, from TOML (config/client.toml, compiled in
// as the default). Every key is optional; unknown keys and out-of-range values are
// errors naming the source and the key.
#pragma once

#include <string>
#include <string_view>

#include "client/net/client_session.hpp"
#include "common/anim/skinning.hpp"
#include "common/base/result.hpp"
#include "common/scene/deform_lod.hpp"

namespace vistel::net {

struct ClientConfig {
  // [network] and [playback]: how sessions behave (room, name and avatar are set by
  // the program).
  SessionSettings session;
  double interpolation_delay_s = 0.1;  // remote postures play this far behind server now
  // [playback]: how far past a member's newest posture its motion is continued before
  // it is held (JitterBuffer::sampleShown); 0 holds at once.
  double max_extrapolation_s = 0.1;
  // [network] netsim: a network simulator spec (net_sim.hpp; checked here, "" = none).
  // --netsim overrides it.
  std::string netsim;
  // [source]
  double idle_rate_hz = 30.0;  // own postures per second when the source has no rate
  // [avatars]
  std::string cache_dir;  // "" = $XDG_CACHE_HOME/vistel/avatars or ~/.cache/vistel/avatars
  // [view]
  int width = 1280;
  int height = 720;
  int worker_threads = 2;
  double frame_rate_hz = 60.0;  // render (or headless sampling) rate
  bool gpu_skinning = true;     // rigid bodies skinned in the vertex shader
  // [view] skinning, the rigid component: "lbs", "dqs", "ffd" (the torso by a lattice
  // along the spine) or "slerp" (rigid + slerp). The vertex shader skins with dqs only:
  // with any other method bodies are skinned on the CPU (gpu_skinning then applies only to
  // bodies whose ffd fell back to dqs for want of a spine).
  SkinningMethod skinning = SkinningMethod::kDualQuaternion;
  // [deform]
  bool deform = true;               // run the deformable component on the drawn bodies
  bool server_interactions = true;  // use the server's Step 1 lists (else compute locally)
  // [lod]: which bodies deform at full rate, at a lower rate or not at all
  DeformLodSettings lod;
};

Result<ClientConfig> parseClientConfig(std::string_view toml_text, std::string_view source_name);
// readConfigText(path) + parseClientConfig ("config/client.toml" falls back to the
// embedded copy).
Result<ClientConfig> loadClientConfig(const std::string& path);

// The avatar cache folder to use for a config value ("" = the user's cache folder).
std::string avatarCacheFolder(const std::string& configured);

}  // namespace vistel::net
