// ConfigTable: typed, range-checked reading of one table of a TOML settings file. Every
// key is optional (an absent key leaves the value as it is); a key of the wrong type or
// out of range, and a key that no read asked for (checkUnknown), is an error naming the
// source, the section and the key.
#pragma once

#include <optional>
#include <set>
#include <string>
#include <string_view>

#include <toml++/toml.h>
#include <glm/glm.hpp>

#include "common/base/result.hpp"

namespace vistel {

// A settings file's text parsed; a syntax error is an Error naming the source and where
// ("server.toml: expected ... (line 3, column 7)"). toml++ reports those by exception:
// they stop here.
Result<toml::table> parseConfigText(std::string_view toml_text, std::string_view source_name);

// In a function returning Status or Result: returns the error of a failed Status.
#define VISTEL_CONFIG_TRY(expr)   \
  do {                            \
    Status st_ = (expr);          \
    if (!st_) return st_.error(); \
  } while (false)

class ConfigTable {
 public:
  // The top-level table [section] of root (absent: every read keeps its default).
  ConfigTable(const toml::table& root, std::string_view section, std::string_view source);
  // A table that is not a top-level section (an entry of an array of tables), named
  // `section` in messages; null reads nothing.
  ConfigTable(const toml::table* table, std::string section, std::string_view source);

  template <typename T>
  Status number(std::string_view key, T& out, double min, double max) {
    std::optional<double> v;
    if (Status st = numberValue(key, v, min, max); !st) return st;
    if (v) out = static_cast<T>(*v);
    return {};
  }
  Status string(std::string_view key, std::string& out);
  Status boolean(std::string_view key, bool& out);
  // Three numbers [x, y, z], each within [min, max].
  Status vec3(std::string_view key, glm::vec3& out, double min, double max);

  // The node of `key` (null when absent), counted as known: for keys of other kinds.
  const toml::node* node(std::string_view key);
  // An error about `key`: "<source>: [<section>] <key>: <what>".
  Error error(std::string_view key, std::string_view what) const;
  // Fails on a key that no read asked for.
  Status checkUnknown() const;

 private:
  Status numberValue(std::string_view key, std::optional<double>& out, double min, double max);

  std::string_view source_;
  std::string section_;
  const toml::table* table_ = nullptr;
  std::set<std::string, std::less<>> known_;
};

}  // namespace vistel
