// The one place the server includes Boost.Asio. Boost 1.74's Asio uses std::exchange
// without including <utility>, which g++ 12 in C++20 mode does not pull in otherwise.
#pragma once

#include <utility>

#include <boost/asio.hpp>

namespace vistel::server {
namespace asio = boost::asio;
}  // namespace vistel::server
