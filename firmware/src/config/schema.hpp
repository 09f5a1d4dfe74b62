#pragma once
// The configuration schema: one row per key with its type, unit, range and meaning. This is the
// single place where keys are documented (config/README.md is generated from it).
#include <functional>
#include <string_view>
#include <variant>
#include <vector>

#include "firmware/config/daemon_config.hpp"

namespace firmware::config_schema {

using FieldRef = std::variant<double*, int64_t*, bool*, std::string*>;

struct FieldSpec {
  std::string_view key;   // dotted path, e.g. "supervisor.tracker_timeout_ms"
  std::string_view unit;  // "ms", "m", "-" ...
  std::string_view doc;
  std::function<FieldRef(DaemonConfig&)> ref;
  double min = 0;  // numbers: inclusive range
  double max = 0;
  // strings: allowed values; an entry ending in ':' allows any value with that prefix.
  std::vector<std::string_view> choices;
};

const std::vector<FieldSpec>& fields();

}  // namespace firmware::config_schema
