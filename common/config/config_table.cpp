#include "common/config/config_table.hpp"

#include <sstream>

namespace vistel {
namespace {

std::optional<double> asNumber(const toml::node& n) {
  if (auto i = n.value_exact<std::int64_t>()) return static_cast<double>(*i);
  if (auto f = n.value_exact<double>()) return *f;
  return std::nullopt;
}

}  // namespace

Result<toml::table> parseConfigText(std::string_view toml_text, std::string_view source_name) {
  try {
    return toml::parse(toml_text, source_name);
  } catch (const toml::parse_error& e) {
    std::ostringstream where;
    where << e.source().begin;
    return fail("{}: {} ({})", source_name, e.description(), where.str());
  }
}

ConfigTable::ConfigTable(const toml::table& root, std::string_view section, std::string_view source)
    : source_(source), section_(section) {
  if (const toml::node* n = root.get(section)) table_ = n->as_table();
}

ConfigTable::ConfigTable(const toml::table* table, std::string section, std::string_view source)
    : source_(source), section_(std::move(section)), table_(table) {}

const toml::node* ConfigTable::node(std::string_view key) {
  known_.insert(std::string(key));
  return table_ != nullptr ? table_->get(key) : nullptr;
}

Error ConfigTable::error(std::string_view key, std::string_view what) const {
  return fail("{}: [{}] {}: {}", source_, section_, key, what);
}

Status ConfigTable::numberValue(std::string_view key, std::optional<double>& out, double min,
                                double max) {
  const toml::node* n = node(key);
  if (n == nullptr) return {};
  const std::optional<double> v = asNumber(*n);
  if (!v) return error(key, "expected a number");
  if (!(*v >= min && *v <= max)) {
    return fail("{}: [{}] {} = {}: out of range [{}, {}]", source_, section_, key, *v, min, max);
  }
  out = v;
  return {};
}

Status ConfigTable::string(std::string_view key, std::string& out) {
  const toml::node* n = node(key);
  if (n == nullptr) return {};
  auto s = n->value_exact<std::string>();
  if (!s) return error(key, "expected a string");
  out = *s;
  return {};
}

Status ConfigTable::boolean(std::string_view key, bool& out) {
  const toml::node* n = node(key);
  if (n == nullptr) return {};
  auto b = n->value_exact<bool>();
  if (!b) return error(key, "expected true or false");
  out = *b;
  return {};
}

Status ConfigTable::vec3(std::string_view key, glm::vec3& out, double min, double max) {
  const toml::node* n = node(key);
  if (n == nullptr) return {};
  const toml::array* a = n->as_array();
  if (a == nullptr || a->size() != 3) return error(key, "expected an array of three numbers");
  glm::vec3 v(0.0f);
  for (std::size_t i = 0; i < 3; ++i) {
    const std::optional<double> x = asNumber((*a)[i]);
    if (!x) return error(key, "expected an array of three numbers");
    if (!(*x >= min && *x <= max)) {
      return fail("{}: [{}] {}[{}] = {}: out of range [{}, {}]", source_, section_, key, i, *x, min,
                  max);
    }
    v[static_cast<glm::length_t>(i)] = static_cast<float>(*x);
  }
  out = v;
  return {};
}

Status ConfigTable::checkUnknown() const {
  if (table_ == nullptr) return {};
  for (const auto& [key, node] : *table_) {
    if (!known_.count(key.str())) {
      return fail("{}: [{}] unknown key '{}'", source_, section_, key.str());
    }
  }
  return {};
}

}  // namespace vistel
