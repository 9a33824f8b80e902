// Bytes of the static implicit model, for the .vavatar file (three chunks, e.g. "PRIM",
// "GRPH", "CALB") and for the network (a server needs only the first two). Little-endian,
// each section starting with its own u32 version; floats are stored bit-exactly, derived
// fields (prepared shapes, the collision matrix) are rebuilt on decode, so a model
// decodes to exactly what was encoded.
//
// Decoders never trust their input: every count is checked against the bytes left, the
// section must be consumed exactly, and the result is validated (validatePrimitiveSet and
// friends). Errors name the section, the element and the reason.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "common/base/bytes.hpp"
#include "common/base/result.hpp"
#include "common/deform/implicit_model.hpp"

namespace vistel {

inline constexpr std::uint32_t kPrimitiveSetVersion = 2;
inline constexpr std::uint32_t kCombinationGraphVersion = 1;
inline constexpr std::uint32_t kCalibrationVersion = 2;  // 2: own_weight

void encodePrimitiveSet(const PrimitiveSet& set, ByteWriter& out);
void encodeCombinationGraph(const CombinationGraph& graph, ByteWriter& out);
void encodeCalibration(const Calibration& calibration, ByteWriter& out);

// joint_count: the skeleton's (bones must be below it).
Result<PrimitiveSet> decodePrimitiveSet(std::span<const std::uint8_t> bytes, int joint_count);
// Finalized against `set`.
Result<CombinationGraph> decodeCombinationGraph(std::span<const std::uint8_t> bytes,
                                                const PrimitiveSet& set);
// vertex_count: the skin's.
Result<Calibration> decodeCalibration(std::span<const std::uint8_t> bytes, const PrimitiveSet& set,
                                      int vertex_count);

// The three sections one after another, each prefixed by its u32 byte size.
std::vector<std::uint8_t> encodeImplicitModel(const ImplicitModel& model);
Result<ImplicitModel> decodeImplicitModel(std::span<const std::uint8_t> bytes, int joint_count,
                                          int vertex_count);

}  // namespace vistel
