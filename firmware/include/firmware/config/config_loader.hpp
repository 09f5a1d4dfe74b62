#pragma once
// Loading and validation of companiond's YAML configuration.
//
// The built-in defaults (config/companiond.yaml, embedded at build time) are applied first, then
// the given file, which may set any subset of keys. Anything doubtful refuses to load: unknown
// key, duplicate key, wrong type, out-of-range value, unreadable file, YAML syntax error. The
// error names the file, line and key.
#include <optional>
#include <string>
#include <vector>

#include "firmware/config/daemon_config.hpp"

namespace firmware {

struct ConfigError {
  std::string file;
  int line = 0;  // 1-based; 0 when not known
  std::string key;
  std::string message;
  [[nodiscard]] std::string to_string() const;
};

struct ConfigResult {
  std::optional<DaemonConfig> config;
  std::vector<ConfigError> errors;  // empty when config is set
  [[nodiscard]] bool ok() const { return config.has_value(); }
};

// Defaults only.
ConfigResult load_default_config();
// Defaults, then the YAML file at `path`.
ConfigResult load_config_file(const std::string& path);
// Defaults, then YAML text (`origin` names it in errors).
ConfigResult load_config_text(const std::string& yaml, const std::string& origin);

// Effective configuration as YAML (every key, with units in the key names).
std::string print_config(const DaemonConfig& config);
// Markdown reference of every key (the content of config/README.md).
std::string config_reference_markdown();
// The built-in default YAML text.
const std::string& default_config_yaml();

}  // namespace firmware
