// Where vistel's generated data lives (the default avatar, the bundled gesture clips):
// $VISTEL_DATA_DIR if set; else the build's data folder (compile definition
// VISTEL_BUILD_DATA_DIR) if it exists; else <folder of the executable>/../data.
#pragma once

#include <string>

namespace vistel::net {

std::string findDataDir();

// <data dir>/default.vavatar
std::string defaultAvatarPath();

}  // namespace vistel::net
