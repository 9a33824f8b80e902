#include "offline/tool/tool_commands.hpp"

#include <algorithm>
#include <cctype>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "common/avatar/avatar_io.hpp"
#include "offline/gltf/gltf_import.hpp"

namespace vistel {
namespace {

std::string lowerExtension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

// The first bytes of a file (fewer when it is shorter; empty when it cannot be read).
std::string fileHead(const std::string& path, std::size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string head(n, '\0');
  in.read(head.data(), static_cast<std::streamsize>(n));
  head.resize(static_cast<std::size_t>(std::max<std::streamsize>(in.gcount(), 0)));
  return head;
}

}  // namespace

void setCommandAction(CLI::App* command, std::function<Status()> body) {
  const std::string name = command->get_name();
  command->callback([name, body = std::move(body)]() {
    std::string message;
    try {
      if (Status s = body(); !s) message = s.error().message;
    } catch (const std::bad_alloc&) {
      message = "out of memory";
    } catch (const std::exception& e) {
      message = e.what();
    }
    if (!message.empty()) {
      std::cerr << "vistel-avatar " << name << ": error: " << message << std::endl;
      throw CLI::RuntimeError(1);
    }
  });
}

Result<AvatarModel> loadAvatarFile(const std::string& path, std::vector<std::string>* warnings) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return fail("{}: no such file", path);
  if (std::filesystem::is_directory(path, ec))
    return fail("{}: is a folder, not an avatar file", path);
  const std::string head = fileHead(path, 8);
  const std::string ext = lowerExtension(path);
  const bool vavatar =
      head.rfind("VAVATAR", 0) == 0 || (head.rfind("glTF", 0) != 0 && ext == ".vavatar");
  if (vavatar) return loadAvatar(path);
  GltfImportReport report;
  Result<AvatarModel> avatar = importGltfAvatar(path, {}, &report);
  if (warnings != nullptr) {
    warnings->insert(warnings->end(), report.warnings.begin(), report.warnings.end());
  }
  return avatar;
}

}  // namespace vistel
