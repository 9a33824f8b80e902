// Writing a cut part as a mesh file through OpenMesh's writers (the format from the
// extension: .obj, .ply, .off or .stl), with its texture coordinates where it has them and
// the format carries them (OBJ, PLY).
#pragma once

#include <string>

#include "common/base/result.hpp"
#include "offline/parts/avatar_cut.hpp"

namespace vistel {

Status writePartMesh(const std::string& path, const CutPart& part);

}  // namespace vistel
