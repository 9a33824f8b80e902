// hidapi's wide-character strings (error texts, product names) as ASCII for logs and
// messages: characters beyond ASCII become '?'. A null string gives "".
#pragma once

#include <string>

namespace vistel {

inline std::string hidText(const wchar_t* w) {
  std::string out;
  for (; w != nullptr && *w != 0; ++w) out.push_back(*w < 128 ? static_cast<char>(*w) : '?');
  return out;
}

}  // namespace vistel
