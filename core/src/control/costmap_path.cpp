#include "core/control/costmap_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace core {

const char* to_string(CostmapPathResult r) {
  switch (r) {
    case CostmapPathResult::kFound:
      return "found";
    case CostmapPathResult::kStartOffMap:
      return "start off the map";
    case CostmapPathResult::kGoalOffMap:
      return "goal off the map";
    case CostmapPathResult::kGoalBlocked:
      return "goal blocked";
    case CostmapPathResult::kNoWay:
      return "no way";
    case CostmapPathResult::kTooManyExpansions:
      return "too many expansions";
  }
  return "?";
}

bool segment_crosses(const Costmap& map, Point2 a, Point2 b, double cost) {
  const double length = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
  const int steps = std::max(1, static_cast<int>(std::ceil(length / (0.5 * map.resolution()))));
  for (int i = 0; i <= steps; ++i) {
    const double f = static_cast<double>(i) / steps;
    if (map.at(a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m)) >= cost) return true;
  }
  return false;
}

void CostmapPathPlanner::set_map(const Costmap& map, double cell_m) {
  const int fine = map.cells();
  const int factor = std::max(1, static_cast<int>(std::lround(cell_m / map.resolution())));
  n_ = fine > 0 ? (fine + factor - 1) / factor : 0;
  cell_m_ = map.resolution() * factor;
  ox_ = map.origin_x();
  oy_ = map.origin_y();
  const auto cells = static_cast<size_t>(n_) * static_cast<size_t>(n_);
  if (cost_.size() != cells) {  // a new size: the only allocation
    cost_.assign(cells, 0);
    g_.assign(cells, 0.0f);
    parent_.assign(cells, -1);
    closed_.assign(cells, 0);
  }
  // The worst costmap cell under each planning cell (cells past the map's edge: lethal, as
  // Costmap::cell has them).
  for (int cj = 0; cj < n_; ++cj) {
    for (int ci = 0; ci < n_; ++ci) {
      uint8_t worst = 0;
      for (int dj = 0; dj < factor; ++dj) {
        for (int di = 0; di < factor; ++di)
          worst = std::max(worst, map.cell(ci * factor + di, cj * factor + dj));
      }
      cost_[static_cast<size_t>(cj) * static_cast<size_t>(n_) + static_cast<size_t>(ci)] = worst;
    }
  }
}

CostmapPathResult CostmapPathPlanner::plan(Point2 start, Point2 goal,
                                           const CostmapPathConfig& config,
                                           std::vector<Point2>& path) {
  path.clear();
  expansions_ = 0;
  if (n_ <= 0) return CostmapPathResult::kStartOffMap;  // no map, or an empty one
  auto index_of = [&](Point2 p, int& i, int& j) {
    const double gx = (p.x_m - ox_) / cell_m_;
    const double gy = (p.y_m - oy_) / cell_m_;
    if (!(gx >= 0 && gy >= 0 && gx < n_ && gy < n_)) return false;  // NaN: off the map
    i = static_cast<int>(gx);
    j = static_cast<int>(gy);
    return true;
  };
  int si = 0, sj = 0, gi = 0, gj = 0;
  if (!index_of(start, si, sj)) return CostmapPathResult::kStartOffMap;
  if (!index_of(goal, gi, gj)) return CostmapPathResult::kGoalOffMap;
  const auto n = static_cast<size_t>(n_);
  const auto at = [n](int i, int j) { return static_cast<size_t>(j) * n + static_cast<size_t>(i); };
  // A goal where the footprint would touch (q^d beside an obstacle) is still reached; in the
  // lethal core it is not.
  if (cost_[at(gi, gj)] >= std::max(config.blocked_cost, static_cast<double>(kCostLethal))) {
    return CostmapPathResult::kGoalBlocked;
  }

  std::fill(g_.begin(), g_.end(), std::numeric_limits<float>::infinity());
  std::fill(closed_.begin(), closed_.end(), uint8_t{0});
  open_.clear();
  // Each expansion pushes at most 8 entries: reserved once for the bound, no allocation after.
  const size_t most_entries = 8 * static_cast<size_t>(std::max(config.max_expansions, 0)) + 8;
  if (open_.capacity() < std::min(most_entries, 8 * cost_.size())) {
    open_.reserve(std::min(most_entries, 8 * cost_.size()));
  }
  // Per metre of a cell: the cheapest is 1, so the octile distance never overestimates.
  auto metre_cost = [&](uint8_t c) {
    const double cd = c;
    if (cd >= config.blocked_cost) {
      return static_cast<float>(1.0 + config.cost_weight + config.unsafe_penalty +
                                config.blocked_penalty);
    }
    return static_cast<float>(cd >= config.unsafe_cost
                                  ? 1.0 + config.cost_weight + config.unsafe_penalty
                                  : 1.0 + config.cost_weight * cd / 100.0);
  };
  const auto h = [&](int i, int j) {
    const auto dx = static_cast<float>(std::abs(i - gi));
    const auto dy = static_cast<float>(std::abs(j - gj));
    return static_cast<float>(cell_m_) * (std::max(dx, dy) + 0.41421356f * std::min(dx, dy));
  };
  const auto later = [](const Open& a, const Open& b) { return a.f > b.f; };  // min-heap
  const size_t s = at(si, sj);
  const size_t target = at(gi, gj);
  g_[s] = 0.0f;
  parent_[s] = -1;
  open_.push_back({h(si, sj), static_cast<int32_t>(s)});
  constexpr int kDi[8] = {1, -1, 0, 0, 1, 1, -1, -1};
  constexpr int kDj[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  const auto step_m = static_cast<float>(cell_m_);
  const float diagonal_m = step_m * 1.41421356f;
  bool found = false;
  while (!open_.empty()) {
    std::pop_heap(open_.begin(), open_.end(), later);
    const Open top = open_.back();
    open_.pop_back();
    const auto c = static_cast<size_t>(top.cell);
    if (closed_[c] != 0) continue;  // a stale entry (a cheaper one came first)
    closed_[c] = 1;
    if (c == target) {
      found = true;
      break;
    }
    if (++expansions_ > config.max_expansions) return CostmapPathResult::kTooManyExpansions;
    const int ci = static_cast<int>(c % n);
    const int cj = static_cast<int>(c / n);
    const float here = metre_cost(cost_[c]);
    // From a blocked cell (the robot in an obstacle's core) the path may go on through blocked
    // cells, at blocked_penalty a metre: the shortest way out, not on through the obstacle.
    const bool escaping = cost_[c] >= config.blocked_cost;
    for (int d = 0; d < 8; ++d) {
      const int ni = ci + kDi[d];
      const int nj = cj + kDj[d];
      if (ni < 0 || nj < 0 || ni >= n_ || nj >= n_) continue;
      const size_t m = at(ni, nj);
      if (closed_[m] != 0) continue;
      if (!escaping && m != target &&
          (cost_[m] >= config.blocked_cost ||
           (d >= 4 && (cost_[at(ni, cj)] >= config.blocked_cost ||
                       cost_[at(ci, nj)] >= config.blocked_cost)))) {
        continue;  // not into a blocked cell, nor diagonally past one's corner
      }
      const float g = g_[c] + (d < 4 ? step_m : diagonal_m) * 0.5f * (here + metre_cost(cost_[m]));
      if (g < g_[m]) {
        g_[m] = g;
        parent_[m] = static_cast<int32_t>(c);
        open_.push_back({g + h(ni, nj), static_cast<int32_t>(m)});
        std::push_heap(open_.begin(), open_.end(), later);
      }
    }
  }
  if (!found) return CostmapPathResult::kNoWay;
  // Back from the goal: the cell centres strictly between the start's and the goal's cells.
  for (int32_t c = parent_[target]; c >= 0 && static_cast<size_t>(c) != s; c = parent_[c]) {
    const auto cu = static_cast<size_t>(c);
    const size_t column = cu % n;
    const size_t row = cu / n;
    path.push_back({ox_ + (static_cast<double>(column) + 0.5) * cell_m_,
                    oy_ + (static_cast<double>(row) + 0.5) * cell_m_});
  }
  path.push_back(start);
  std::reverse(path.begin(), path.end());
  path.push_back(goal);
  return CostmapPathResult::kFound;
}

}  // namespace core
