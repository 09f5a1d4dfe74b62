#pragma once
// Recorded pedestrian trajectories in the plain `frame person_id x_m y_m` format of the
// trajectory-prediction datasets (ETH/UCY: one observation per line, whitespace separated,
// every column a float). Times: frame values are turned into seconds with the frame period the
// caller gives (seconds between two consecutive frame values present in the file; 0.4 s for
// the ETH/UCY files, whose frame numbers step by 10 at 25 fps).
#include <map>
#include <string>
#include <vector>

#include "sim/trajectory.hpp"

namespace sim {

struct PedestrianDataset {
  std::map<int, Trajectory> people;  // by id; t = 0 at the file's first frame
  double frame_step = 0;             // smallest difference between consecutive frame values
  size_t rows = 0;
};

struct DatasetLoad {
  bool ok = false;
  PedestrianDataset data;
  std::string error;  // "<file>:<line>: ..." when not ok
};

DatasetLoad parse_pedestrian_dataset(const std::string& text, double frame_period_s,
                                     const std::string& name = "<text>");
DatasetLoad load_pedestrian_dataset(const std::string& path, double frame_period_s);

// The id of the person who walks the farthest (a good default to follow); -1 when empty.
int longest_walk(const PedestrianDataset& dataset);
// The ids of the `n` people who walk the farthest, the farthest first (equal walks: the lower
// id first); fewer when the file has fewer people.
std::vector<int> longest_walks(const PedestrianDataset& dataset, size_t n);

}  // namespace sim
