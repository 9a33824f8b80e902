#include "common/avatar/avatar_io.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <optional>

#include <openssl/evp.h>

#include "common/base/bytes.hpp"
#include "common/base/file.hpp"
#include "common/deform/implicit_codec.hpp"

namespace vistel {
namespace {

constexpr char kMagic[8] = {'V', 'A', 'V', 'A', 'T', 'A', 'R', '\0'};
constexpr std::uint32_t kMaxJoints = 4096;
constexpr std::uint32_t kMaxVertices = 16u << 20;
constexpr std::uint32_t kMaxChunks = 64;

using Tag = std::array<char, 4>;

std::string tagName(const Tag& t) { return std::string(t.data(), 4); }

// Writes one chunk: tag, payload size, payload, CRC-32 of the payload.
void writeChunk(ByteWriter& w, const char (&tag)[5], const std::vector<std::uint8_t>& payload) {
  w.raw(tag, 4);
  w.u32(static_cast<std::uint32_t>(payload.size()));
  w.raw(payload.data(), payload.size());
  w.u32(crc32(payload));
}

void writeTransform(ByteWriter& w, const Transform& t) {
  for (int i = 0; i < 3; ++i) w.f32(t.translation[i]);
  w.f32(t.rotation.w);
  w.f32(t.rotation.x);
  w.f32(t.rotation.y);
  w.f32(t.rotation.z);
  for (int i = 0; i < 3; ++i) w.f32(t.scale[i]);
}

Transform readTransform(ByteReader& r) {
  Transform t;
  for (int i = 0; i < 3; ++i) t.translation[i] = r.f32();
  t.rotation.w = r.f32();
  t.rotation.x = r.f32();
  t.rotation.y = r.f32();
  t.rotation.z = r.f32();
  for (int i = 0; i < 3; ++i) t.scale[i] = r.f32();
  return t;
}

std::vector<std::uint8_t> encodeSkeleton(const Skeleton& s) {
  std::vector<std::uint8_t> out;
  ByteWriter w(out);
  w.u32(static_cast<std::uint32_t>(s.jointCount()));
  for (int j = 0; j < s.jointCount(); ++j) {
    const auto u = static_cast<std::size_t>(j);
    w.string(s.names[u]);
    w.i32(s.parents[u]);
    writeTransform(w, s.rest_local[u]);
    w.raw(&s.inverse_bind[u], sizeof(glm::mat4));
  }
  return out;
}

Result<Skeleton> decodeSkeleton(std::span<const std::uint8_t> payload) {
  ByteReader r(payload);
  const std::uint32_t n = r.u32();
  if (!r.ok() || n == 0 || n > kMaxJoints) return fail("joint count {} is out of range", n);
  Skeleton s;
  s.names.resize(n);
  s.parents.resize(n);
  s.rest_local.resize(n);
  s.inverse_bind.resize(n);
  for (std::uint32_t j = 0; j < n && r.ok(); ++j) {
    s.names[j] = r.string(256);
    s.parents[j] = r.i32();
    s.rest_local[j] = readTransform(r);
    r.raw(&s.inverse_bind[j], sizeof(glm::mat4));
  }
  if (!r.ok()) return fail("truncated at byte {}", r.offset());
  if (r.remaining() != 0) return fail("{} unexpected bytes after the joints", r.remaining());
  if (Status v = validateSkeleton(s); !v) return v.error();
  for (const glm::mat4& m : s.inverse_bind) {
    for (int c = 0; c < 4; ++c) {
      for (int k = 0; k < 4; ++k) {
        if (!std::isfinite(m[c][k])) return fail("non-finite inverse bind matrix");
      }
    }
  }
  return s;
}

std::vector<std::uint8_t> encodeSkin(const SkinMesh& m) {
  std::vector<std::uint8_t> out;
  ByteWriter w(out);
  w.u32(static_cast<std::uint32_t>(m.positions.size()));
  w.u32(static_cast<std::uint32_t>(m.indices.size()));
  w.u32(static_cast<std::uint32_t>(m.influences));
  w.array(std::span<const glm::vec3>(m.positions));
  w.array(std::span<const glm::vec3>(m.normals));
  w.array(std::span<const std::uint32_t>(m.indices));
  w.array(std::span<const std::uint16_t>(m.joints));
  w.array(std::span<const float>(m.weights));
  return out;
}

Result<SkinMesh> decodeSkin(std::span<const std::uint8_t> payload, int joint_count) {
  ByteReader r(payload);
  const std::uint32_t nvert = r.u32();
  const std::uint32_t nindex = r.u32();
  const std::uint32_t k = r.u32();
  if (!r.ok()) return fail("truncated header");
  if (nvert > kMaxVertices || nindex > 3 * 2 * kMaxVertices) {
    return fail("{} vertices / {} indices is beyond the limits", nvert, nindex);
  }
  if (k < 1 || k > static_cast<std::uint32_t>(kMaxInfluences))
    return fail("{} influences per vertex", k);
  SkinMesh m;
  m.influences = static_cast<int>(k);
  r.array(m.positions, nvert);
  r.array(m.normals, nvert);
  r.array(m.indices, nindex);
  r.array(m.joints, std::size_t{nvert} * k);
  r.array(m.weights, std::size_t{nvert} * k);
  if (!r.ok()) return fail("truncated: the sizes in the header need more bytes than the chunk has");
  if (r.remaining() != 0) return fail("{} unexpected bytes after the arrays", r.remaining());
  if (Status v = validateSkinMesh(m, joint_count); !v) return v.error();
  return m;
}

// The look (avatar_look.hpp): uvs, textures, materials, submeshes.
std::vector<std::uint8_t> encodeLook(const AvatarLook& look) {
  std::vector<std::uint8_t> out;
  ByteWriter w(out);
  w.u32(static_cast<std::uint32_t>(look.uvs.size()));
  w.array(std::span<const glm::vec2>(look.uvs));
  w.u32(static_cast<std::uint32_t>(look.textures.size()));
  for (const AvatarTexture& t : look.textures) {
    w.string(t.name);
    w.string(t.mime);
    w.u32(static_cast<std::uint32_t>(t.width));
    w.u32(static_cast<std::uint32_t>(t.height));
    w.u32(static_cast<std::uint32_t>(t.encoded.size()));
    w.raw(t.encoded.data(), t.encoded.size());
  }
  w.u32(static_cast<std::uint32_t>(look.materials.size()));
  for (const AvatarMaterial& m : look.materials) {
    w.string(m.name);
    for (int c = 0; c < 4; ++c) w.f32(m.base_color[c]);
    w.i32(m.base_color_texture);
    w.i32(m.normal_texture);
    w.f32(m.normal_scale);
    w.f32(m.metallic);
    w.f32(m.roughness);
    w.u8(static_cast<std::uint8_t>(m.alpha_mode));
    w.f32(m.alpha_cutoff);
    w.u8(m.double_sided ? 1 : 0);
  }
  w.u32(static_cast<std::uint32_t>(look.submeshes.size()));
  for (const AvatarSubmesh& sm : look.submeshes) {
    w.u32(sm.first_index);
    w.u32(sm.index_count);
    w.i32(sm.material);
  }
  return out;
}

Result<AvatarLook> decodeLook(std::span<const std::uint8_t> payload, const SkinMesh& skin) {
  ByteReader r(payload);
  AvatarLook look;
  const std::uint32_t nuv = r.u32();
  if (!r.ok() || (nuv != 0 && nuv != skin.positions.size())) {
    return fail("{} texture coordinates for {} vertices", nuv, skin.positions.size());
  }
  r.array(look.uvs, nuv);
  const std::uint32_t ntex = r.u32();
  if (!r.ok() || ntex > static_cast<std::uint32_t>(kMaxLookTextures)) {
    return fail("truncated, or {} textures (at most {})", ntex, kMaxLookTextures);
  }
  look.textures.resize(ntex);
  for (AvatarTexture& t : look.textures) {
    t.name = r.string(kMaxLookNameBytes);
    t.mime = r.string(64);
    t.width = static_cast<int>(std::min<std::uint32_t>(r.u32(), 1u << 30));
    t.height = static_cast<int>(std::min<std::uint32_t>(r.u32(), 1u << 30));
    const std::uint32_t size = r.u32();
    if (!r.ok() || size > kMaxTextureBytes) return fail("truncated texture, or {} bytes", size);
    r.array(t.encoded, size);
    if (!r.ok()) return fail("texture '{}': truncated at byte {}", t.name, r.offset());
  }
  const std::uint32_t nmat = r.u32();
  if (!r.ok() || nmat > static_cast<std::uint32_t>(kMaxLookMaterials)) {
    return fail("truncated, or {} materials (at most {})", nmat, kMaxLookMaterials);
  }
  look.materials.resize(nmat);
  for (AvatarMaterial& m : look.materials) {
    m.name = r.string(kMaxLookNameBytes);
    for (int c = 0; c < 4; ++c) m.base_color[c] = r.f32();
    m.base_color_texture = r.i32();
    m.normal_texture = r.i32();
    m.normal_scale = r.f32();
    m.metallic = r.f32();
    m.roughness = r.f32();
    const std::uint8_t mode = r.u8();
    if (mode > 2) return fail("material '{}': unknown alpha mode {}", m.name, mode);
    m.alpha_mode = static_cast<AlphaMode>(mode);
    m.alpha_cutoff = r.f32();
    m.double_sided = r.u8() != 0;
  }
  const std::uint32_t nsub = r.u32();
  if (!r.ok() || nsub > skin.indices.size() / 3) {
    return fail("truncated, or {} submeshes for {} triangles", nsub, skin.indices.size() / 3);
  }
  look.submeshes.resize(nsub);
  for (AvatarSubmesh& sm : look.submeshes) {
    sm.first_index = r.u32();
    sm.index_count = r.u32();
    sm.material = r.i32();
  }
  if (!r.ok()) return fail("truncated at byte {}", r.offset());
  if (r.remaining() != 0) return fail("{} unexpected bytes after the submeshes", r.remaining());
  if (Status v = validateLook(look, skin.positions.size(), skin.indices.size()); !v) {
    return v.error();
  }
  return look;
}

}  // namespace

std::vector<std::uint8_t> encodeAvatar(const AvatarModel& avatar) {
  std::vector<std::uint8_t> meta;
  ByteWriter(meta).string(avatar.name);

  std::vector<std::uint8_t> out;
  ByteWriter w(out);
  w.raw(kMagic, sizeof kMagic);
  w.u32(kAvatarFormatVersion);
  const bool has_look = !avatar.look.empty() || !avatar.look.submeshes.empty();
  w.u32((avatar.implicit ? 6 : 3) + (has_look ? 1 : 0));
  writeChunk(w, "META", meta);
  writeChunk(w, "SKEL", encodeSkeleton(avatar.skeleton));
  writeChunk(w, "SKIN", encodeSkin(avatar.skin));
  if (avatar.implicit) {
    // The deformable component: primitives, combination graph, calibration.
    std::vector<std::uint8_t> prim, graph, calib;
    ByteWriter wp(prim), wg(graph), wc(calib);
    encodePrimitiveSet(avatar.implicit->primitives, wp);
    encodeCombinationGraph(avatar.implicit->graph, wg);
    encodeCalibration(avatar.implicit->calibration, wc);
    writeChunk(w, "PRIM", prim);
    writeChunk(w, "GRPH", graph);
    writeChunk(w, "CALB", calib);
  }
  if (has_look) writeChunk(w, "LOOK", encodeLook(avatar.look));
  return out;
}

Result<AvatarModel> decodeAvatar(std::span<const std::uint8_t> bytes, std::string_view source) {
  ByteReader r(bytes);
  char magic[8] = {};
  if (!r.raw(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof magic) != 0) {
    return fail("{}: not a vistel avatar (bad magic)", source);
  }
  const std::uint32_t version = r.u32();
  const std::uint32_t chunks = r.u32();
  if (!r.ok()) return fail("{}: truncated header", source);
  if (version < kAvatarOldestFormatVersion || version > kAvatarFormatVersion) {
    return fail("{}: format version {} (this build reads versions {} to {})", source, version,
                kAvatarOldestFormatVersion, kAvatarFormatVersion);
  }
  if (chunks > kMaxChunks) return fail("{}: {} chunks is beyond the limit", source, chunks);

  AvatarModel avatar;
  bool have_meta = false, have_skel = false, have_skin = false;
  std::span<const std::uint8_t> skin_payload;
  std::optional<std::span<const std::uint8_t>> prim_payload, graph_payload, calib_payload;
  std::optional<std::span<const std::uint8_t>> look_payload;
  for (std::uint32_t c = 0; c < chunks; ++c) {
    // Read and check one chunk.
    const std::size_t at = r.offset();
    Tag tag{};
    r.raw(tag.data(), 4);
    const std::uint32_t size = r.u32();
    if (!r.ok()) return fail("{}: chunk {} at byte {}: truncated chunk header", source, c, at);
    const auto payload = r.bytes(size);
    const std::uint32_t stored_crc = r.u32();
    if (!r.ok()) {
      return fail("{}: chunk '{}' at byte {}: payload of {} bytes runs past the end of the file",
                  source, tagName(tag), at, size);
    }
    if (crc32(payload) != stored_crc) {
      return fail("{}: chunk '{}' at byte {}: checksum mismatch (corrupted)", source, tagName(tag),
                  at);
    }
    // Decode the chunks this version knows; skip others (forward compatible).
    const std::string name = tagName(tag);
    if (name == "META") {
      ByteReader m(payload);
      avatar.name = m.string(1024);
      if (!m.ok()) return fail("{}: chunk 'META': truncated name", source);
      have_meta = true;
    } else if (name == "SKEL") {
      auto s = decodeSkeleton(payload);
      if (!s) return fail("{}: chunk 'SKEL': {}", source, s.error().message);
      avatar.skeleton = std::move(*s);
      have_skel = true;
    } else if (name == "SKIN") {
      skin_payload = payload;
      have_skin = true;
    } else if (name == "PRIM") {
      prim_payload = payload;
    } else if (name == "GRPH") {
      graph_payload = payload;
    } else if (name == "CALB") {
      calib_payload = payload;
    } else if (name == "LOOK" && version >= 2) {
      look_payload = payload;
    }
  }
  if (r.remaining() != 0) return fail("{}: {} bytes after the last chunk", source, r.remaining());
  if (!have_meta || !have_skel || !have_skin) {
    return fail("{}: missing chunk(s):{}{}{}", source, have_meta ? "" : " META",
                have_skel ? "" : " SKEL", have_skin ? "" : " SKIN");
  }
  auto skin = decodeSkin(skin_payload, avatar.skeleton.jointCount());
  if (!skin) return fail("{}: chunk 'SKIN': {}", source, skin.error().message);
  avatar.skin = std::move(*skin);
  if (look_payload) {
    auto look = decodeLook(*look_payload, avatar.skin);
    if (!look) return fail("{}: chunk 'LOOK': {}", source, look.error().message);
    avatar.look = std::move(*look);
  }

  // The deformable component: all three chunks or none.
  const int present = (prim_payload ? 1 : 0) + (graph_payload ? 1 : 0) + (calib_payload ? 1 : 0);
  if (present == 0) return avatar;
  if (present != 3) {
    return fail("{}: the implicit model needs chunks PRIM, GRPH and CALB; missing:{}{}{}", source,
                prim_payload ? "" : " PRIM", graph_payload ? "" : " GRPH",
                calib_payload ? "" : " CALB");
  }
  auto prim = decodePrimitiveSet(*prim_payload, avatar.skeleton.jointCount());
  if (!prim) return fail("{}: chunk 'PRIM': {}", source, prim.error().message);
  auto graph = decodeCombinationGraph(*graph_payload, *prim);
  if (!graph) return fail("{}: chunk 'GRPH': {}", source, graph.error().message);
  auto calib = decodeCalibration(*calib_payload, *prim, avatar.skin.vertexCount());
  if (!calib) return fail("{}: chunk 'CALB': {}", source, calib.error().message);
  avatar.implicit = ImplicitModel{std::move(*prim), std::move(*graph), std::move(*calib)};
  if (Status v = validateAvatar(avatar); !v) return withContext(source, v.error());
  return avatar;
}

Status saveAvatar(const AvatarModel& avatar, const std::string& path) {
  if (Status v = validateAvatar(avatar); !v) return withContext(path, v.error());
  return writeFileBytes(path, encodeAvatar(avatar));
}

Result<AvatarModel> loadAvatar(const std::string& path) {
  auto bytes = readFileBytes(path, std::size_t{1} << 30);
  if (!bytes) return bytes.error();
  return decodeAvatar(*bytes, path);
}

std::string avatarContentHash(std::span<const std::uint8_t> encoded) {
  std::array<unsigned char, EVP_MAX_MD_SIZE> digest{};
  unsigned int length = 0;
  EVP_Digest(encoded.data(), encoded.size(), digest.data(), &length, EVP_sha256(), nullptr);
  std::string hex;
  hex.reserve(2 * length);
  for (unsigned int i = 0; i < length; ++i) hex += fmt::format("{:02x}", digest[i]);
  return hex;
}

}  // namespace vistel
