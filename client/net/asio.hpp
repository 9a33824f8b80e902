// The one place client/net includes Boost.Asio. Boost 1.74's Asio uses std::exchange
// without including <utility>, which g++ 12 in C++20 mode does not pull in otherwise.
#pragma once

#include <utility>

#include <boost/asio.hpp>

namespace vistel::net {
namespace asio = boost::asio;
}  // namespace vistel::net
