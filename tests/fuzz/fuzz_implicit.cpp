// libFuzzer target: decodeImplicitModel (common/deform/implicit_codec.hpp), the bytes of an
// avatar's implicit model as they arrive in a .vavatar chunk or from the network.
//
// Input layout: byte 0 is the skeleton's joint count - 1, bytes 1-2 the skin's vertex count
// (u16, little-endian), the rest the encoded model. Properties: nothing crashes, leaks or
// reads out of bounds; an accepted model validates against those counts, and encoding it
// and decoding again gives the same model (compared through its encoding).
// Seeds: balls from makeBall (one sphere primitive, calibrated on an icosphere) and a
// three-primitive model (two limbs blending through a joint) built from one.
#include <cstdint>
#include <span>
#include <vector>

#include "common/deform/implicit_codec.hpp"
#include "common/deform/implicit_model.hpp"
#include "common/deform/prop.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

using namespace vistel;
using fuzz::check;

constexpr std::size_t kPrefix = 3;  // joint count - 1, vertex count (u16)

std::vector<std::uint8_t> withPrefix(int joint_count, int vertex_count,
                                     const ImplicitModel& model) {
  std::vector<std::uint8_t> out = {static_cast<std::uint8_t>(joint_count - 1),
                                   static_cast<std::uint8_t>(vertex_count & 0xff),
                                   static_cast<std::uint8_t>(vertex_count >> 8)};
  const std::vector<std::uint8_t> body = encodeImplicitModel(model);
  out.insert(out.end(), body.begin(), body.end());
  check(decodeImplicitModel(std::span(out).subspan(kPrefix), joint_count, vertex_count).ok(),
        "a seed model decodes");
  return out;
}

std::vector<fuzz::Seed> makeSeeds() {
  std::vector<fuzz::Seed> seeds;
  for (int subdivisions : {0, 1}) {
    BallSpec spec;
    spec.subdivisions = subdivisions;
    spec.stiffness = subdivisions == 0 ? kRigidStiffness : 2.0e4f;
    spec.elasticity = subdivisions == 0 ? Elasticity::kElastic : Elasticity::kViscoelastic;
    Result<BallBody> ball = makeBall(spec);
    check(ball.ok(), "makeBall builds the seed");
    seeds.push_back({"ball_s" + std::to_string(subdivisions) + ".bin",
                     withPrefix(1, ball->mesh.vertexCount(), ball->model)});
  }

  // Two limbs and the joint between them, on three bones; the ball's vertices stay on
  // the first limb.
  Result<BallBody> ball = makeBall(BallSpec{});
  check(ball.ok(), "makeBall builds the seed");
  ImplicitModel model = ball->model;
  Primitive limb = model.primitives.items[0];
  model.primitives.items.clear();
  for (int k = 0; k < 3; ++k) {
    Primitive p = limb;
    p.name = k == 0 ? "upper" : k == 1 ? "lower" : "elbow";
    p.role = k == 2 ? PrimitiveRole::kJoint : PrimitiveRole::kLimb;
    p.bone = k;
    p.collides = k != 2;
    model.primitives.items.push_back(p);
  }
  model.graph.blends = {Blend{0, 1, 2}};
  model.graph.collide_pairs = {{0, 1}};
  finalizeGraph(model.graph, 3);
  check(validateImplicitModel(model, 3, ball->mesh.vertexCount()).ok(),
        "the three-primitive seed validates");
  seeds.push_back({"limbs_joint.bin", withPrefix(3, ball->mesh.vertexCount(), model)});
  return seeds;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int* argc, char*** argv) {
  fuzz::writeSeedsIfAsked(*argc, *argv, makeSeeds);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < kPrefix) return 0;
  const int joint_count = 1 + data[0];
  const int vertex_count = data[1] | (data[2] << 8);
  const std::span<const std::uint8_t> bytes(data + kPrefix, size - kPrefix);

  Result<ImplicitModel> model = decodeImplicitModel(bytes, joint_count, vertex_count);
  if (!model.ok()) {
    check(!model.error().message.empty(), "a rejection says why");
    return 0;
  }
  check(validateImplicitModel(*model, joint_count, vertex_count).ok(),
        "an accepted model validates");

  // Round trip: the decoded model re-encodes to bytes that decode to the same model.
  const std::vector<std::uint8_t> encoded = encodeImplicitModel(*model);
  Result<ImplicitModel> again = decodeImplicitModel(encoded, joint_count, vertex_count);
  check(again.ok(), "the re-encoded model decodes");
  check(encodeImplicitModel(*again) == encoded, "decode(encode(model)) is the same model");
  return 0;
}
