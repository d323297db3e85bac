#pragma once
#include <span>
#include <string_view>

namespace pdamp::schema {

/// migrations()[i] takes a store from user_version i to i + 1.
std::span<const std::string_view> migrations();

}  // namespace pdamp::schema
