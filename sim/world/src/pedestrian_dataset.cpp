#include "sim/pedestrian_dataset.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <set>
#include <sstream>

namespace sim {

namespace {
struct Row {
  double frame, x, y;
  int id;
};

// A day of recording: frame values spanning more than this are not frame numbers.
constexpr double kMaxDurationS = 86400.0;
// Positions in metres: beyond a thousand kilometres they are not a scene's (and the walk's
// velocities would overflow).
constexpr double kMaxCoordinateM = 1e6;
// Seconds between frames: from a 1 kHz tracker to a frame a minute.
constexpr double kMinFramePeriodS = 1e-3;
constexpr double kMaxFramePeriodS = 60.0;

bool parse_double(const std::string& token, double& out) {
  errno = 0;
  char* end = nullptr;
  out = std::strtod(token.c_str(), &end);
  return errno == 0 && end == token.c_str() + token.size() && std::isfinite(out);
}
}  // namespace

DatasetLoad parse_pedestrian_dataset(const std::string& text, double frame_period_s,
                                     const std::string& name) {
  DatasetLoad r;
  if (!(frame_period_s >= kMinFramePeriodS && frame_period_s <= kMaxFramePeriodS)) {
    r.error = fmt::format("{}: frame period must be {} to {} s (got {})", name, kMinFramePeriodS,
                          kMaxFramePeriodS, frame_period_s);
    return r;
  }
  std::vector<Row> rows;
  std::istringstream in(text);
  std::string line;
  size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream fields(line);
    std::vector<std::string> tok;
    for (std::string t; fields >> t;)
      tok.push_back(t);
    if (tok.empty() || tok[0][0] == '#') continue;
    if (tok.size() != 4) {
      r.error = fmt::format("{}:{}: expected 4 columns 'frame id x y', got {}", name, line_no,
                            tok.size());
      return r;
    }
    double v[4];
    for (size_t i = 0; i < 4; ++i) {
      if (!parse_double(tok[i], v[i])) {
        r.error =
            fmt::format("{}:{}: column {} is not a number: '{}'", name, line_no, i + 1, tok[i]);
        return r;
      }
    }
    if (v[1] != std::floor(v[1]) || std::abs(v[1]) > 1e9) {
      r.error =
          fmt::format("{}:{}: person id must be a whole number, got '{}'", name, line_no, tok[1]);
      return r;
    }
    if (std::abs(v[2]) > kMaxCoordinateM || std::abs(v[3]) > kMaxCoordinateM) {
      r.error = fmt::format("{}:{}: position ({}, {}) is more than {:.0f} km out: not metres", name,
                            line_no, tok[2], tok[3], kMaxCoordinateM / 1000);
      return r;
    }
    rows.push_back({v[0], v[2], v[3], static_cast<int>(v[1])});
  }
  if (rows.empty()) {
    r.error = fmt::format("{}: no observations", name);
    return r;
  }
  std::set<double> frames;
  for (const Row& row : rows)
    frames.insert(row.frame);
  double step = 0;
  for (auto it = std::next(frames.begin()); it != frames.end(); ++it) {
    const double d = *it - *std::prev(it);
    if (step == 0 || d < step) step = d;
  }
  if (step == 0) step = 1;  // a single frame: any period works
  const double first = *frames.begin();
  std::map<int, std::vector<TimedPose>> by_id;
  for (const Row& row : rows) {
    const double t = (row.frame - first) / step * frame_period_s;
    if (!std::isfinite(t) || t > kMaxDurationS) {
      r.error =
          fmt::format("{}: frame {} is {} s after the first: not a recording", name, row.frame, t);
      return r;
    }
    by_id[row.id].push_back({t, {row.x, row.y, 0.0}});
  }
  for (auto& [id, samples] : by_id) {
    std::stable_sort(samples.begin(), samples.end(),
                     [](const TimedPose& a, const TimedPose& b) { return a.t_s < b.t_s; });
    // One observation per frame: a repeated frame of the same person keeps the first.
    samples.erase(
        std::unique(samples.begin(), samples.end(),
                    [](const TimedPose& a, const TimedPose& b) { return a.t_s == b.t_s; }),
        samples.end());
    set_headings_from_motion(samples);
    r.data.people.emplace(id, Trajectory(std::move(samples)));
  }
  r.data.frame_step = step;
  r.data.rows = rows.size();
  r.ok = true;
  return r;
}

int longest_walk(const PedestrianDataset& dataset) {
  const std::vector<int> ids = longest_walks(dataset, 1);
  return ids.empty() ? -1 : ids.front();
}

std::vector<int> longest_walks(const PedestrianDataset& dataset, size_t n) {
  std::vector<std::pair<double, int>> walks;  // (path length, id), in id order
  for (const auto& [id, tr] : dataset.people)
    walks.emplace_back(path_length(tr), id);
  std::stable_sort(walks.begin(), walks.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<int> ids;
  for (size_t i = 0; i < std::min(n, walks.size()); ++i)
    ids.push_back(walks[i].second);
  return ids;
}

DatasetLoad load_pedestrian_dataset(const std::string& path, double frame_period_s) {
  std::ifstream f(path);
  if (!f) {
    DatasetLoad r;
    r.error = fmt::format("{}: cannot open", path);
    return r;
  }
  std::stringstream ss;
  ss << f.rdbuf();
  return parse_pedestrian_dataset(ss.str(), frame_period_s, path);
}

}  // namespace sim
