#pragma once
// The learned selector's runtime: an MLP read from a policy file, evaluated on Eigen without
// allocation, with a masked argmax over the collision-free points.
//
// Policy file, version 1 (little-endian, no padding):
//   char[8]  magic "CMPPOL01"
//   u32      format version (1)
//   u32      observation layout id (see observation.hpp; must match the runtime's)
//   u32      n: interactive-space points = the output size (must match the configuration)
//   u32      input size (must match the layout for n)
//   u32      L: number of layers
//   f32[in]  normalisation mean, then f32[in] standard deviation (> 0): x' = (x - mean) / std
//   L times: u32 in, u32 out, u32 activation (0 none, 1 ReLU, 2 tanh),
//            f32[out * in] weights (row-major: out rows), f32[out] bias
// The file ends there (trailing bytes are an error). Layer i's in = layer i-1's out; the first
// in = input size; the last out = n. Every number must be finite.
#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace core {

enum class Activation : uint8_t { kNone = 0, kRelu = 1, kTanh = 2 };

struct DenseLayer {
  Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> weights;  // out x in
  Eigen::VectorXf bias;
  Activation activation = Activation::kNone;
};

struct PolicyFile {
  uint32_t layout_id = 0;
  uint32_t points = 0;
  Eigen::VectorXf mean;
  Eigen::VectorXf stddev;
  std::vector<DenseLayer> layers;
};

struct PolicyLoadResult {
  std::optional<PolicyFile> policy;
  std::string error;  // what is wrong, with the offending value
};

// `expected_layout` / `expected_points` / `expected_input` come from the runtime.
PolicyLoadResult parse_policy(std::span<const uint8_t> bytes, uint32_t expected_layout,
                              uint32_t expected_points, uint32_t expected_input);
PolicyLoadResult load_policy_file(const std::string& path, uint32_t expected_layout,
                                  uint32_t expected_points, uint32_t expected_input);
// The file's bytes (for tests and the training tools).
std::vector<uint8_t> encode_policy(const PolicyFile& p);

class MlpPolicy {
 public:
  explicit MlpPolicy(PolicyFile file);

  // Logits for a raw (unnormalised) observation; the returned view is valid until the next call.
  const Eigen::VectorXf& logits(std::span<const float> observation);
  // argmax of the logits over the points with mask[i] true; -1 when none is. Ties: lowest index.
  int select(std::span<const float> observation, std::span<const bool> mask);

  [[nodiscard]] size_t input_size() const { return static_cast<size_t>(file_.mean.size()); }
  [[nodiscard]] uint32_t points() const { return file_.points; }

 private:
  PolicyFile file_;
  std::vector<Eigen::VectorXf> activations_;  // one buffer per layer output (allocated once)
  Eigen::VectorXf input_;
};

}  // namespace core
