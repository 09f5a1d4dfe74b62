#include "firmware/config/config_loader.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "amfitrack/open_link.hpp"
#include "hal/net/udp_socket.hpp"
#include "schema.hpp"

namespace firmware {
namespace {

using config_schema::FieldRef;
using config_schema::FieldSpec;

const std::map<std::string_view, const FieldSpec*>& field_index() {
  static const auto kIndex = [] {
    std::map<std::string_view, const FieldSpec*> m;
    for (const auto& f : config_schema::fields())
      m.emplace(f.key, &f);
    return m;
  }();
  return kIndex;
}

bool has_child_keys(std::string_view prefix) {
  const auto& idx = field_index();
  const std::string p = std::string(prefix) + ".";
  const auto it = idx.lower_bound(p);
  return it != idx.end() && it->first.substr(0, p.size()) == p;
}

std::string fmt_number(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

class Loader {
 public:
  Loader(DaemonConfig& cfg, std::string origin, std::vector<ConfigError>& errors,
         std::set<std::string>* seen)
      : cfg_(cfg), origin_(std::move(origin)), errors_(errors), seen_(seen) {}

  void walk(const YAML::Node& node, const std::string& prefix) {
    if (!node.IsMap()) {
      error(node, prefix,
            prefix.empty() ? "top level must be a mapping of sections"
                           : "expected a mapping (section) here");
      return;
    }
    std::set<std::string> keys_here;
    for (const auto& kv : node) {
      const YAML::Node& k = kv.first;
      const YAML::Node& v = kv.second;
      if (!k.IsScalar()) {
        error(k, prefix, "keys must be plain names");
        continue;
      }
      const std::string name = k.Scalar();
      std::string path = prefix;
      if (!path.empty()) path += '.';
      path += name;
      if (!keys_here.insert(name).second) {
        error(k, path, "duplicate key");
        continue;
      }
      const auto& idx = field_index();
      if (const auto it = idx.find(path); it != idx.end()) {
        assign(*it->second, v, path);
      } else if (has_child_keys(path)) {
        walk(v, path);
      } else {
        error(k, path, "unknown key");
      }
    }
  }

 private:
  void error(const YAML::Node& at, const std::string& key, const std::string& message) {
    const YAML::Mark mark = at.Mark();
    errors_.push_back(ConfigError{origin_, mark.is_null() ? 0 : mark.line + 1, key, message});
  }

  void assign(const FieldSpec& f, const YAML::Node& v, const std::string& path) {
    if (!v.IsScalar()) {
      error(v, path,
            "expected a single value, got a " + std::string(v.IsMap()        ? "mapping"
                                                            : v.IsSequence() ? "list"
                                                                             : "null"));
      return;
    }
    if (seen_ != nullptr) seen_->insert(path);
    FieldRef ref = f.ref(cfg_);
    const std::string& text = v.Scalar();
    if (auto* d = std::get_if<double*>(&ref)) {
      double x = 0;
      if (!YAML::convert<double>::decode(v, x) || !std::isfinite(x)) {
        error(v, path, "expected a finite number, got '" + text + "'");
      } else if (x < f.min || x > f.max) {
        error(v, path,
              "value " + text + " out of range [" + fmt_number(f.min) + ", " + fmt_number(f.max) +
                  "] " + std::string(f.unit));
      } else {
        **d = x;
      }
    } else if (auto* i = std::get_if<int64_t*>(&ref)) {
      int64_t x = 0;
      if (!YAML::convert<int64_t>::decode(v, x)) {
        error(v, path, "expected an integer, got '" + text + "'");
      } else if (static_cast<double>(x) < f.min || static_cast<double>(x) > f.max) {
        error(v, path,
              "value " + text + " out of range [" + fmt_number(f.min) + ", " + fmt_number(f.max) +
                  "] " + std::string(f.unit));
      } else {
        **i = x;
      }
    } else if (auto* b = std::get_if<bool*>(&ref)) {
      bool x = false;
      if (!YAML::convert<bool>::decode(v, x)) {
        error(v, path, "expected true or false, got '" + text + "'");
      } else {
        **b = x;
      }
    } else if (auto* s = std::get_if<std::string*>(&ref)) {
      bool allowed = f.choices.empty();
      for (const auto c : f.choices) {
        const bool prefix = !c.empty() && c.back() == ':';
        if ((prefix && text.size() > c.size() && text.compare(0, c.size(), c) == 0) ||
            (!prefix && text == c)) {
          allowed = true;
        }
      }
      if (!allowed) {
        std::string list;
        for (const auto c : f.choices)
          list += (list.empty() ? "" : ", ") + std::string(c) + (c.back() == ':' ? "..." : "");
        error(v, path, "'" + text + "' is not one of: " + list);
      } else {
        **s = text;
      }
    }
  }

  DaemonConfig& cfg_;
  std::string origin_;
  std::vector<ConfigError>& errors_;
  std::set<std::string>* seen_;
};

bool parse(const std::string& text, const std::string& origin, YAML::Node& out,
           std::vector<ConfigError>& errors) {
  try {
    out = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    errors.push_back(ConfigError{origin, e.mark.is_null() ? 0 : e.mark.line + 1, "",
                                 "YAML syntax error: " + e.msg});
    return false;
  }
  return true;
}

// Applies the built-in defaults; every schema key must be set by them.
bool apply_defaults(DaemonConfig& cfg, std::vector<ConfigError>& errors) {
  YAML::Node root;
  const std::string origin = "<built-in defaults>";
  if (!parse(default_config_yaml(), origin, root, errors)) return false;
  std::set<std::string> seen;
  Loader(cfg, origin, errors, &seen).walk(root, "");
  for (const auto& f : config_schema::fields()) {
    if (seen.count(std::string(f.key)) == 0) {
      errors.push_back(ConfigError{origin, 0, std::string(f.key), "no default value"});
    }
  }
  return errors.empty();
}

// 1-based line of a dotted key in the document, 0 when it is not there (a default).
int line_of(const YAML::Node& node, std::string_view key) {
  if (!node.IsMap()) return 0;
  const size_t dot = key.find('.');
  const YAML::Node child = node[std::string(key.substr(0, dot))];  // const lookup: adds nothing
  if (!child.IsDefined()) return 0;
  if (dot == std::string_view::npos) return child.Mark().is_null() ? 0 : child.Mark().line + 1;
  return line_of(child, key.substr(dot + 1));
}

// Rules between keys (each key's own range is in the schema).
void check_relations(const DaemonConfig& cfg, const YAML::Node& root, const std::string& origin,
                     std::vector<ConfigError>& errors) {
  auto require = [&](bool ok, std::string_view key, const std::string& message) {
    if (!ok) errors.push_back(ConfigError{origin, line_of(root, key), std::string(key), message});
  };
  require(cfg.tracker.quality_good_min >= cfg.tracker.quality_bad_below, "tracker.quality_good_min",
          "must be >= tracker.quality_bad_below (" + std::to_string(cfg.tracker.quality_bad_below) +
              "): the hysteresis needs it");
  if (cfg.devices.tracker.rfind("hid:", 0) == 0 || cfg.devices.tracker.rfind("serial:", 0) == 0) {
    std::string why;
    require(amfitrack::parse_link_uri(cfg.devices.tracker, &why).has_value(), "devices.tracker",
            why);
  }
  if (cfg.devices.lidar.rfind("udp:", 0) == 0) {
    hal::UdpEndpoint ep;
    std::string why;
    require(hal::parse_udp_endpoint(cfg.devices.lidar, ep, why), "devices.lidar", why);
  }
  require(cfg.costmap.z_max_m > cfg.costmap.z_min_m &&
              (cfg.costmap.z_max_m - cfg.costmap.z_min_m) / cfg.costmap.resolution_m <= 64.0,
          "costmap.z_max_m",
          "the height band z_min_m..z_max_m must be above zero and at most 64 voxels high");
  require(cfg.costmap.inflation_radius_m >= cfg.costmap.inscribed_radius_m,
          "costmap.inflation_radius_m", "must be >= costmap.inscribed_radius_m");
  // The path sample is lane 4 of the structured samples' block: without the block it would be
  // silently ignored.
  require(!cfg.mppi.path_guide || cfg.mppi.guide_samples, "mppi.path_guide",
          "needs mppi.guide_samples: true (the path sample is one of the structured samples)");
  require(!cfg.mppi.orbit_guide || cfg.mppi.guide_samples, "mppi.orbit_guide",
          "needs mppi.guide_samples: true (the orbit samples are structured samples)");
  require(!cfg.interactive_space.speed_standoff || cfg.closing_speed.robot_decel_mps2 > 0.0,
          "interactive_space.speed_standoff",
          "needs closing_speed.robot_decel_mps2 > 0 (the standoff is the limit's gap)");
  require(cfg.tracker.reconnect_max_ms >= cfg.tracker.reconnect_first_ms,
          "tracker.reconnect_max_ms",
          "must be >= tracker.reconnect_first_ms (" +
              std::to_string(cfg.tracker.reconnect_first_ms) + ")");
}

}  // namespace

std::string ConfigError::to_string() const {
  std::string s = file;
  if (line > 0) s += ":" + std::to_string(line);
  s += ": ";
  if (!key.empty()) s += "'" + key + "': ";
  return s + message;
}

ConfigResult load_default_config() {
  ConfigResult r;
  DaemonConfig cfg;
  if (apply_defaults(cfg, r.errors)) r.config = cfg;
  return r;
}

ConfigResult load_config_text(const std::string& yaml, const std::string& origin) {
  ConfigResult r;
  DaemonConfig cfg;
  if (!apply_defaults(cfg, r.errors)) return r;
  YAML::Node root;
  if (!parse(yaml, origin, root, r.errors)) return r;
  if (!root.IsNull()) Loader(cfg, origin, r.errors, nullptr).walk(root, "");
  if (r.errors.empty()) check_relations(cfg, root, origin, r.errors);
  if (r.errors.empty()) r.config = cfg;
  return r;
}

ConfigResult load_config_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) {
    ConfigResult r;
    r.errors.push_back(ConfigError{path, 0, "", "cannot open configuration file"});
    return r;
  }
  std::stringstream ss;
  ss << in.rdbuf();
  return load_config_text(ss.str(), path);
}

std::string print_config(const DaemonConfig& config) {
  DaemonConfig copy = config;
  std::ostringstream os;
  os << "# effective companiond configuration\n";
  std::string section;
  for (const auto& f : config_schema::fields()) {
    const auto dot = f.key.find('.');
    const std::string sec(f.key.substr(0, dot));
    if (sec != section) {
      os << sec << ":\n";
      section = sec;
    }
    os << "  " << f.key.substr(dot + 1) << ": ";
    std::visit(
        [&](auto* p) {
          using T = std::remove_pointer_t<decltype(p)>;
          if constexpr (std::is_same_v<T, bool>) {
            os << (*p ? "true" : "false");
          } else if constexpr (std::is_same_v<T, std::string>) {
            os << '"' << *p << '"';
          } else {
            os << *p;
          }
        },
        f.ref(copy));
    os << "\n";
  }
  return os.str();
}

std::string config_reference_markdown() {
  const auto defaults = load_default_config();
  DaemonConfig cfg = defaults.config.value_or(DaemonConfig{});
  std::ostringstream os;
  os << "# companiond configuration reference\n\n"
     << "Generated from the schema in `firmware/src/config/schema.cpp` by\n"
     << "`companiond --config-reference`; a unit test fails when this file is out of date.\n"
     << "Defaults are in `config/companiond.yaml` (installed as "
        "`/etc/companion/companiond.yaml`).\n"
     << "A configuration file may set any subset of keys; the rest keep their defaults.\n"
     << "Unknown keys, duplicate keys, wrong types and out-of-range values refuse to load\n"
     << "with the file, line and key named. Check a file with `companiond --check-config FILE`.\n\n"
     << "Task rates, time budgets and thread priorities are not configuration: they live in the\n"
     << "task table (`firmware/src/task_table.cpp`).\n";
  std::string section;
  for (const auto& f : config_schema::fields()) {
    const std::string sec(f.key.substr(0, f.key.find('.')));
    if (sec != section) {
      os << "\n## " << sec
         << "\n\n| key | unit | default | allowed | meaning |\n|---|---|---|---|---|\n";
      section = sec;
    }
    std::string def;
    std::string allowed;
    std::visit(
        [&](auto* p) {
          using T = std::remove_pointer_t<decltype(p)>;
          if constexpr (std::is_same_v<T, bool>) {
            def = *p ? "true" : "false";
            allowed = "true, false";
          } else if constexpr (std::is_same_v<T, std::string>) {
            def = "`" + *p + "`";
            for (const auto c : f.choices) {
              allowed += (allowed.empty() ? "" : ", ") + std::string("`") + std::string(c) +
                         (c.back() == ':' ? "…" : "") + "`";
            }
          } else {
            def = fmt_number(static_cast<double>(*p));
            allowed = fmt_number(f.min) + " … " + fmt_number(f.max);
          }
        },
        f.ref(cfg));
    os << "| `" << f.key << "` | " << f.unit << " | " << def << " | " << allowed << " | " << f.doc
       << " |\n";
  }
  return os.str();
}

}  // namespace firmware
