#include "core/policy/mlp_policy.hpp"

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>

namespace core {
namespace {

constexpr char kMagic[8] = {'C', 'M', 'P', 'P', 'O', 'L', '0', '1'};
constexpr uint32_t kFormatVersion = 1;

class Reader {
 public:
  explicit Reader(std::span<const uint8_t> b) : b_(b) {}
  bool u32(uint32_t& v) {
    if (pos_ + 4 > b_.size()) return false;
    v = static_cast<uint32_t>(b_[pos_]) | static_cast<uint32_t>(b_[pos_ + 1]) << 8 |
        static_cast<uint32_t>(b_[pos_ + 2]) << 16 | static_cast<uint32_t>(b_[pos_ + 3]) << 24;
    pos_ += 4;
    return true;
  }
  bool floats(float* out, size_t n) {
    if (n > (b_.size() - pos_) / 4) return false;
    for (size_t i = 0; i < n; ++i) {
      uint32_t u = 0;
      (void)u32(u);
      std::memcpy(&out[i], &u, 4);
    }
    return true;
  }
  bool bytes(void* out, size_t n) {
    if (pos_ + n > b_.size()) return false;
    std::memcpy(out, b_.data() + pos_, n);
    pos_ += n;
    return true;
  }
  [[nodiscard]] size_t remaining() const { return b_.size() - pos_; }
  [[nodiscard]] size_t pos() const { return pos_; }

 private:
  std::span<const uint8_t> b_;
  size_t pos_ = 0;
};

void put_u32(std::vector<uint8_t>& v, uint32_t x) {
  for (int i = 0; i < 4; ++i)
    v.push_back(static_cast<uint8_t>(x >> (8 * i)));
}
void put_floats(std::vector<uint8_t>& v, const float* f, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    uint32_t u = 0;
    std::memcpy(&u, &f[i], 4);
    put_u32(v, u);
  }
}

bool all_finite(const float* f, size_t n) {
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(f[i])) return false;
  }
  return true;
}

PolicyLoadResult fail(std::string why) {
  return PolicyLoadResult{std::nullopt, "policy file: " + std::move(why)};
}

}  // namespace

PolicyLoadResult parse_policy(std::span<const uint8_t> bytes, uint32_t expected_layout,
                              uint32_t expected_points, uint32_t expected_input) {
  Reader r(bytes);
  char magic[8] = {};
  if (!r.bytes(magic, 8) || std::memcmp(magic, kMagic, 8) != 0) {
    return fail("not a companion policy (magic 'CMPPOL01' missing)");
  }
  uint32_t version = 0, layout = 0, points = 0, input = 0, layers = 0;
  if (!r.u32(version) || !r.u32(layout) || !r.u32(points) || !r.u32(input) || !r.u32(layers)) {
    return fail("truncated header");
  }
  if (version != kFormatVersion) {
    return fail("format version " + std::to_string(version) + ", this runtime reads 1");
  }
  if (layout != expected_layout) {
    return fail("observation layout id " + std::to_string(layout) + ", the runtime builds " +
                std::to_string(expected_layout) + " (retrain or use a matching build)");
  }
  if (points != expected_points) {
    return fail("trained for n = " + std::to_string(points) +
                " interactive-space points, configured n = " + std::to_string(expected_points));
  }
  if (input != expected_input) {
    return fail("input size " + std::to_string(input) + ", the layout needs " +
                std::to_string(expected_input));
  }
  if (layers == 0 || layers > 16) return fail("layer count " + std::to_string(layers));
  PolicyFile p;
  p.layout_id = layout;
  p.points = points;
  p.mean.resize(input);
  p.stddev.resize(input);
  if (!r.floats(p.mean.data(), input) || !r.floats(p.stddev.data(), input)) {
    return fail("truncated normalisation statistics");
  }
  if (!all_finite(p.mean.data(), input) || !all_finite(p.stddev.data(), input)) {
    return fail("normalisation statistics are not all finite");
  }
  for (uint32_t i = 0; i < input; ++i) {
    if (!(p.stddev[i] > 0.0f)) {
      return fail("standard deviation of input " + std::to_string(i) + " is not > 0");
    }
  }
  uint32_t prev = input;
  for (uint32_t l = 0; l < layers; ++l) {
    uint32_t in = 0, out = 0, act = 0;
    if (!r.u32(in) || !r.u32(out) || !r.u32(act)) return fail("truncated layer header");
    const std::string where = "layer " + std::to_string(l) + ": ";
    if (in != prev) {
      return fail(where + "input " + std::to_string(in) + " does not follow the previous output " +
                  std::to_string(prev));
    }
    if (out == 0 || out > 4096) return fail(where + "output size " + std::to_string(out));
    if (act > 2) return fail(where + "unknown activation " + std::to_string(act));
    DenseLayer d;
    d.weights.resize(out, in);
    d.bias.resize(out);
    d.activation = static_cast<Activation>(act);
    if (!r.floats(d.weights.data(), static_cast<size_t>(out) * in) ||
        !r.floats(d.bias.data(), out)) {
      return fail(where + "truncated weights");
    }
    if (!all_finite(d.weights.data(), static_cast<size_t>(out) * in) ||
        !all_finite(d.bias.data(), out)) {
      return fail(where + "weights are not all finite (NaN/Inf)");
    }
    p.layers.push_back(std::move(d));
    prev = out;
  }
  if (prev != points) {
    return fail("the last layer has " + std::to_string(prev) +
                " outputs, n = " + std::to_string(points));
  }
  if (r.remaining() != 0) {
    return fail(std::to_string(r.remaining()) + " bytes after the last layer");
  }
  return PolicyLoadResult{std::move(p), {}};
}

PolicyLoadResult load_policy_file(const std::string& path, uint32_t expected_layout,
                                  uint32_t expected_points, uint32_t expected_input) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return fail("cannot read " + path);
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
  PolicyLoadResult r = parse_policy(bytes, expected_layout, expected_points, expected_input);
  if (!r.policy) r.error = path + ": " + r.error;
  return r;
}

std::vector<uint8_t> encode_policy(const PolicyFile& p) {
  std::vector<uint8_t> v(kMagic, kMagic + 8);
  put_u32(v, kFormatVersion);
  put_u32(v, p.layout_id);
  put_u32(v, p.points);
  put_u32(v, static_cast<uint32_t>(p.mean.size()));
  put_u32(v, static_cast<uint32_t>(p.layers.size()));
  put_floats(v, p.mean.data(), static_cast<size_t>(p.mean.size()));
  put_floats(v, p.stddev.data(), static_cast<size_t>(p.stddev.size()));
  for (const DenseLayer& l : p.layers) {
    put_u32(v, static_cast<uint32_t>(l.weights.cols()));
    put_u32(v, static_cast<uint32_t>(l.weights.rows()));
    put_u32(v, static_cast<uint32_t>(l.activation));
    put_floats(v, l.weights.data(), static_cast<size_t>(l.weights.size()));
    put_floats(v, l.bias.data(), static_cast<size_t>(l.bias.size()));
  }
  return v;
}

MlpPolicy::MlpPolicy(PolicyFile file) : file_(std::move(file)), input_(file_.mean.size()) {
  for (const DenseLayer& l : file_.layers)
    activations_.emplace_back(l.weights.rows());
}

const Eigen::VectorXf& MlpPolicy::logits(std::span<const float> observation) {
  const Eigen::Map<const Eigen::VectorXf> x(observation.data(),
                                            static_cast<Eigen::Index>(observation.size()));
  input_ = (x - file_.mean).cwiseQuotient(file_.stddev);
  const Eigen::VectorXf* in = &input_;
  for (size_t l = 0; l < file_.layers.size(); ++l) {
    const DenseLayer& layer = file_.layers[l];
    Eigen::VectorXf& out = activations_[l];
    out.noalias() = layer.weights * *in;
    out += layer.bias;
    if (layer.activation == Activation::kRelu) {
      out = out.cwiseMax(0.0f);
    } else if (layer.activation == Activation::kTanh) {
      out = out.array().tanh();
    }
    in = &out;
  }
  return *in;
}

int MlpPolicy::select(std::span<const float> observation, std::span<const bool> mask) {
  const Eigen::VectorXf& z = logits(observation);
  int best = -1;
  for (Eigen::Index i = 0; i < z.size() && static_cast<size_t>(i) < mask.size(); ++i) {
    if (mask[static_cast<size_t>(i)] && (best < 0 || z[i] > z[best])) best = static_cast<int>(i);
  }
  return best;
}

}  // namespace core
