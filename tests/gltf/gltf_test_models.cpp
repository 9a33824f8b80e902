#include "tests/gltf/gltf_test_models.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>

#include "common/glb/glb_container.hpp"

namespace vistel::test {
namespace {

std::string base64(const std::vector<std::uint8_t>& data) {
  static const char* kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < data.size(); i += 3) {
    const std::uint32_t v = (data[i] << 16) | (data[i + 1] << 8) | data[i + 2];
    for (int s = 18; s >= 0; s -= 6) out.push_back(kAlphabet[(v >> s) & 63]);
  }
  if (i + 1 == data.size()) {
    const std::uint32_t v = data[i] << 16;
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back('=');
    out.push_back('=');
  } else if (i + 2 == data.size()) {
    const std::uint32_t v = (data[i] << 16) | (data[i + 1] << 8);
    out.push_back(kAlphabet[(v >> 18) & 63]);
    out.push_back(kAlphabet[(v >> 12) & 63]);
    out.push_back(kAlphabet[(v >> 6) & 63]);
    out.push_back('=');
  }
  return out;
}

glm::dmat4 rotation(double angle, const glm::dvec3& axis) {
  return glm::rotate(glm::dmat4(1.0), angle, axis);
}

}  // namespace

GltfBuilder::GltfBuilder() {
  doc = {{"asset", {{"version", "2.0"}, {"generator", "vistel test"}}},
         {"nodes", nlohmann::json::array()},
         {"accessors", nlohmann::json::array()},
         {"bufferViews", nlohmann::json::array()}};
}

int GltfBuilder::addView(const void* data, std::size_t size, int stride) {
  while (bin.size() % 4 != 0) bin.push_back(0);
  const std::size_t offset = bin.size();
  bin.resize(offset + size);
  if (size > 0) std::memcpy(bin.data() + offset, data, size);
  nlohmann::json view = {{"buffer", 0}, {"byteOffset", offset}, {"byteLength", size}};
  if (stride != 0) view["byteStride"] = stride;
  doc["bufferViews"].push_back(view);
  return static_cast<int>(doc["bufferViews"].size()) - 1;
}

int GltfBuilder::addNode(const nlohmann::json& node) {
  doc["nodes"].push_back(node);
  return static_cast<int>(doc["nodes"].size()) - 1;
}

std::string GltfBuilder::jsonText(const std::string& buffer_uri) const {
  nlohmann::json out = doc;
  std::size_t padded = (bin.size() + 3) / 4 * 4;
  nlohmann::json buffer = {{"byteLength", buffer_uri.empty() ? padded : bin.size()}};
  if (!buffer_uri.empty()) buffer["uri"] = buffer_uri;
  out["buffers"] = nlohmann::json::array({buffer});
  return out.dump();
}

std::vector<std::uint8_t> GltfBuilder::glb() const { return assembleGlb(jsonText(), bin); }

std::string GltfBuilder::gltfEmbedded() const {
  std::string uri = "data:application/octet-stream;base64,";
  uri.append(base64(bin));
  return jsonText(uri);
}

std::string GltfBuilder::writeGltfWithBin(const std::string& dir, const std::string& stem) const {
  const std::string path = (std::filesystem::path(dir) / (stem + ".gltf")).string();
  const std::string bin_name = stem + ".bin";
  std::ofstream(path) << jsonText(bin_name);
  std::ofstream((std::filesystem::path(dir) / bin_name).string(), std::ios::binary)
      .write(reinterpret_cast<const char*>(bin.data()), static_cast<std::streamsize>(bin.size()));
  return path;
}

nlohmann::json trsOf(const glm::dmat4& m) {
  const glm::dvec3 x(m[0]), y(m[1]), z(m[2]);
  const double s = glm::length(x);
  const glm::dquat q = glm::normalize(glm::quat_cast(glm::dmat3(x / s, y / s, z / s)));
  nlohmann::json node = {{"translation", {m[3].x, m[3].y, m[3].z}},
                         {"rotation", {q.x, q.y, q.z, q.w}}};
  if (std::abs(s - 1.0) > 1e-9) node["scale"] = {s, s, s};
  return node;
}

ChainGltf makeChainGltf(const ChainOptions& opt) {
  ChainGltf out;
  GltfBuilder& b = out.file;
  const int nj = opt.joints;
  const double step = 12.0, z0 = 50.0, radius = 5.0;

  // The conversion node: Z-up centimetres -> Y-up metres.
  const glm::dmat4 conv =
      rotation(-glm::half_pi<double>(), {1, 0, 0}) * glm::scale(glm::dmat4(1.0), glm::dvec3(0.01));
  const glm::dmat4 helper_local =
      rotation(0.7, {0, 1, 0}) * glm::translate(glm::dmat4(1.0), {1.0, 2.0, 3.0});

  // Joint frames in file space (cm, Z up): on the column axis, each with its own rotation.
  std::vector<glm::dmat4> file_world(static_cast<std::size_t>(nj));
  for (int j = 0; j < nj; ++j) {
    file_world[static_cast<std::size_t>(j)] =
        glm::translate(glm::dmat4(1.0), {0.0, 0.0, z0 + step * j}) *
        rotation(0.4 * (j + 1), {0, 0, 1}) * rotation(0.15 * (j % 3), {1, 0, 0});
  }

  // Nodes: conversion root, joint chain (with the helper node), mesh node.
  const int conv_node =
      b.addNode(nlohmann::json(trsOf(rotation(-glm::half_pi<double>(), {1, 0, 0}))));
  b.doc["nodes"][static_cast<std::size_t>(conv_node)]["scale"] = {0.01, 0.01, 0.01};
  b.doc["nodes"][static_cast<std::size_t>(conv_node)]["name"] = "ZUpToYUp";
  int parent_node = conv_node;
  glm::dmat4 parent_file_world(1.0);
  for (int j = 0; j < nj; ++j) {
    if (opt.helper_node && j == 3) {
      nlohmann::json helper = trsOf(helper_local);
      helper["name"] = "helper";
      const int h = b.addNode(helper);
      b.doc["nodes"][static_cast<std::size_t>(parent_node)]["children"].push_back(h);
      parent_node = h;
      parent_file_world = parent_file_world * helper_local;
    }
    const glm::dmat4 local =
        glm::inverse(parent_file_world) * file_world[static_cast<std::size_t>(j)];
    const std::string name = fmt::format("j{}", j);
    nlohmann::json node = trsOf(local);
    node["name"] = name;
    const int n = b.addNode(node);
    b.doc["nodes"][static_cast<std::size_t>(parent_node)]["children"].push_back(n);
    out.joint_nodes.push_back(n);
    out.names.push_back(name);
    parent_node = n;
    parent_file_world = file_world[static_cast<std::size_t>(j)];
  }
  // Expected model frames: the converted position, conv's rotation times the joint's.
  for (int j = 0; j < nj; ++j) {
    const glm::dmat4& fw = file_world[static_cast<std::size_t>(j)];
    glm::dmat4 m = rotation(-glm::half_pi<double>(), {1, 0, 0}) * glm::dmat4(glm::dmat3(fw));
    m[3] = conv * glm::dvec4(glm::dvec3(fw[3]), 1.0);
    out.joint_model.push_back(m);
  }

  // Vertices (file space): rings around the Z axis, two cap centres.
  const int segments = 8;
  const int rings = 2 * nj + 1;
  const double z1 = z0 + step * (nj - 1);
  std::vector<glm::dvec3> file_pos, file_nrm;
  for (int r = 0; r < rings; ++r) {
    const double z = z0 + (z1 - z0) * r / (rings - 1);
    for (int s = 0; s < segments; ++s) {
      const double a = 2.0 * glm::pi<double>() * s / segments;
      file_pos.emplace_back(radius * std::cos(a), radius * std::sin(a), z);
      file_nrm.emplace_back(std::cos(a), std::sin(a), 0.0);
    }
  }
  const auto bottom = static_cast<std::uint32_t>(file_pos.size());
  file_pos.emplace_back(0.0, 0.0, z0);
  file_nrm.emplace_back(0.0, 0.0, -1.0);
  const auto top = static_cast<std::uint32_t>(file_pos.size());
  file_pos.emplace_back(0.0, 0.0, z1);
  file_nrm.emplace_back(0.0, 0.0, 1.0);
  const std::size_t nv = file_pos.size();

  // Triangles, counter-clockwise seen from outside.
  std::vector<std::uint32_t> tris;
  auto at = [&](int r, int s) { return static_cast<std::uint32_t>(r * segments + (s % segments)); };
  for (int r = 0; r + 1 < rings; ++r) {
    for (int s = 0; s < segments; ++s) {
      tris.insert(tris.end(), {at(r, s), at(r, s + 1), at(r + 1, s + 1)});
      tris.insert(tris.end(), {at(r, s), at(r + 1, s + 1), at(r + 1, s)});
    }
  }
  for (int s = 0; s < segments; ++s) {
    tris.insert(tris.end(), {bottom, at(0, s + 1), at(0, s)});
    tris.insert(tris.end(), {top, at(rings - 1, s), at(rings - 1, s + 1)});
  }
  out.triangles = static_cast<int>(tris.size() / 3);

  // Expected model-space geometry.
  const glm::dmat3 conv_rot = glm::dmat3(rotation(-glm::half_pi<double>(), {1, 0, 0}));
  for (std::size_t v = 0; v < nv; ++v) {
    out.positions_model.push_back(glm::dvec3(conv * glm::dvec4(file_pos[v], 1.0)));
    out.normals_model.push_back(conv_rot * file_nrm[v]);
    const glm::dvec3 radial =
        v < bottom ? glm::dvec3(file_pos[v].x, file_pos[v].y, 0.0) / radius : file_nrm[v];
    out.radial_model.push_back(conv_rot * radial);
  }

  // Skin order (skin index -> hierarchy joint) and weights: the 8 joints nearest in height.
  std::vector<int> skin_of_joint(static_cast<std::size_t>(nj));
  std::vector<int> skin_joint_nodes;
  for (int k = 0; k < nj; ++k) {
    const int j = opt.scramble_skin_order ? nj - 1 - k : k;
    skin_of_joint[static_cast<std::size_t>(j)] = k;
    skin_joint_nodes.push_back(out.joint_nodes[static_cast<std::size_t>(j)]);
  }
  std::vector<std::uint8_t> joints0(nv * 4, 0);
  std::vector<float> weights0(nv * 4, 0.0f);
  std::vector<std::uint16_t> joints1(nv * 4, 0);
  std::vector<std::uint16_t> weights1(nv * 4, 0);
  out.weights.resize(nv);
  for (std::size_t v = 0; v < nv; ++v) {
    std::vector<std::pair<double, int>> near;
    for (int j = 0; j < nj; ++j) near.emplace_back(std::abs(file_pos[v].z - (z0 + step * j)), j);
    std::sort(near.begin(), near.end());
    const bool zero = std::find(opt.unweighted.begin(), opt.unweighted.end(),
                                static_cast<int>(v)) != opt.unweighted.end();
    const std::size_t used = std::min<std::size_t>(near.size(), opt.eight_influences ? 8 : 4);
    double total = 0.0;
    std::map<std::string, double> raw;
    for (std::size_t s = 0; s < used && !zero; ++s) {
      const double w = 1.0 / (1.0 + near[s].first / 6.0);
      const int j = near[s].second;
      double effective;
      if (s < 4) {
        joints0[v * 4 + s] = static_cast<std::uint8_t>(skin_of_joint[static_cast<std::size_t>(j)]);
        weights0[v * 4 + s] = static_cast<float>(3.0 * w);  // unnormalised on purpose
        effective = weights0[v * 4 + s];
      } else {
        joints1[v * 4 + s - 4] =
            static_cast<std::uint16_t>(skin_of_joint[static_cast<std::size_t>(j)]);
        weights1[v * 4 + s - 4] = static_cast<std::uint16_t>(std::lround(w * 0.5 * 65535.0));
        effective = weights1[v * 4 + s - 4] / 65535.0;
      }
      raw[out.names[static_cast<std::size_t>(j)]] += effective;
      total += effective;
    }
    for (auto& [name, w] : raw) out.weights[v][name] = w / total;
  }

  // Accessors.
  std::vector<float> pos_data, nrm_data;
  for (std::size_t v = 0; v < nv; ++v) {
    const glm::dvec3 p = opt.mesh_space_ibm ? file_pos[v] : out.positions_model[v];
    const glm::dvec3 n = opt.mesh_space_ibm ? file_nrm[v] : out.normals_model[v];
    pos_data.insert(pos_data.end(),
                    {static_cast<float>(p.x), static_cast<float>(p.y), static_cast<float>(p.z)});
    nrm_data.insert(nrm_data.end(),
                    {static_cast<float>(n.x), static_cast<float>(n.y), static_cast<float>(n.z)});
  }
  nlohmann::json attributes;
  attributes["POSITION"] = b.addAccessor(pos_data, 5126, "VEC3");
  if (opt.normals) attributes["NORMAL"] = b.addAccessor(nrm_data, 5126, "VEC3");
  attributes["JOINTS_0"] = b.addAccessor(joints0, 5121, "VEC4");
  attributes["WEIGHTS_0"] = b.addAccessor(weights0, 5126, "VEC4");
  if (opt.eight_influences) {
    attributes["JOINTS_1"] = b.addAccessor(joints1, 5123, "VEC4");
    attributes["WEIGHTS_1"] = b.addAccessor(weights1, 5123, "VEC4", true);
  }
  nlohmann::json primitive = {{"attributes", attributes}};
  if (opt.index_component == 5121) {
    std::vector<std::uint8_t> idx(tris.begin(), tris.end());
    primitive["indices"] = b.addAccessor(idx, 5121, "SCALAR");
  } else if (opt.index_component == 5123) {
    std::vector<std::uint16_t> idx(tris.begin(), tris.end());
    primitive["indices"] = b.addAccessor(idx, 5123, "SCALAR");
  } else if (opt.index_component == 5125) {
    primitive["indices"] = b.addAccessor(tris, 5125, "SCALAR");
  } else {
    // No indices: every triangle's vertices written out (and the expectations with them).
    ChainOptions flat = opt;
    flat.index_component = 5125;
    ChainGltf indexed = makeChainGltf(flat);
    ChainGltf soup;
    soup.names = indexed.names;
    soup.joint_model = indexed.joint_model;
    soup.joint_nodes = indexed.joint_nodes;
    soup.mesh_node = indexed.mesh_node;
    soup.triangles = indexed.triangles;
    soup.file = indexed.file;
    auto& doc = soup.file.doc;
    nlohmann::json& prim = doc["meshes"][0]["primitives"][0];
    prim.erase("indices");
    // Re-emit each attribute de-indexed.
    for (auto& [name, acc_index] : prim["attributes"].items()) {
      const nlohmann::json acc = doc["accessors"][acc_index.get<std::size_t>()];
      const nlohmann::json view = doc["bufferViews"][acc["bufferView"].get<std::size_t>()];
      const int comp = acc["componentType"];
      const std::size_t csize = comp == 5121 ? 1 : comp == 5123 ? 2 : 4;
      const std::string type = acc["type"];
      const std::size_t ncomp = type == "VEC3" ? 3 : 4;
      const std::size_t esize = csize * ncomp;
      std::vector<std::uint8_t> data;
      for (std::uint32_t i : tris) {
        const std::uint8_t* src =
            soup.file.bin.data() + view["byteOffset"].get<std::size_t>() + i * esize;
        data.insert(data.end(), src, src + esize);
      }
      const int new_view = soup.file.addView(data.data(), data.size());
      nlohmann::json new_acc = acc;
      new_acc["bufferView"] = new_view;
      new_acc["count"] = tris.size();
      doc["accessors"].push_back(new_acc);
      acc_index = doc["accessors"].size() - 1;
    }
    for (std::uint32_t i : tris) {
      soup.positions_model.push_back(indexed.positions_model[i]);
      soup.normals_model.push_back(indexed.normals_model[i]);
      soup.radial_model.push_back(indexed.radial_model[i]);
      soup.weights.push_back(indexed.weights[i]);
    }
    return soup;
  }

  // Skin with inverse bind matrices, mesh, mesh node, scene.
  std::vector<float> ibm;
  const glm::dmat4 mesh_world = opt.mesh_space_ibm ? conv : glm::dmat4(1.0);
  for (int k = 0; k < nj; ++k) {
    const int j = opt.scramble_skin_order ? nj - 1 - k : k;
    const glm::dmat4 world = conv * file_world[static_cast<std::size_t>(j)];
    const glm::dmat4 m = glm::inverse(world) * mesh_world;
    for (int c = 0; c < 4; ++c) {
      for (int r = 0; r < 4; ++r) ibm.push_back(static_cast<float>(m[c][r]));
    }
  }
  b.doc["skins"] = nlohmann::json::array(
      {{{"joints", skin_joint_nodes}, {"inverseBindMatrices", b.addAccessor(ibm, 5126, "MAT4")}}});
  b.doc["meshes"] = nlohmann::json::array({{{"primitives", nlohmann::json::array({primitive})}}});
  out.mesh_node = b.addNode({{"name", "body"}, {"mesh", 0}, {"skin", 0}});
  nlohmann::json roots = nlohmann::json::array({conv_node});
  if (opt.mesh_space_ibm) {
    b.doc["nodes"][static_cast<std::size_t>(conv_node)]["children"].push_back(out.mesh_node);
  } else {
    roots.push_back(out.mesh_node);
  }
  b.doc["scenes"] = nlohmann::json::array({{{"nodes", roots}}});
  b.doc["scene"] = 0;
  return out;
}

std::map<std::string, double> weightsByName(const AvatarModel& avatar, std::size_t v) {
  std::map<std::string, double> out;
  const auto k = static_cast<std::size_t>(avatar.skin.influences);
  for (std::size_t s = 0; s < k; ++s) {
    const float w = avatar.skin.weights[v * k + s];
    if (w > 0.0f) out[avatar.skeleton.names[avatar.skin.joints[v * k + s]]] += w;
  }
  return out;
}

}  // namespace vistel::test
