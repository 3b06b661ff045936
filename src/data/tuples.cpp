// Tuple sampling (context + targets with overlap and baseline spread), view resizing and collation.
#include "data/tuples.h"

#include <torch/torch.h>

#include <algorithm>
#include <mutex>
#include <random>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "geometry/image_ops.h"
#include "io/tensor_image.h"

namespace isplat {

void TupleOptions::visit(ConfigVisitor& v) {
  v.field("targets", targets, "target views per tuple (the paper uses 3)", Range::at_least(1));
  v.field("width", width, "training image width in pixels", Range::at_least(16));
  v.field("height", height, "training image height in pixels", Range::at_least(16));
  v.field("window", window, "targets are drawn from frames within +-window of the context", Range::at_least(1));
  v.field("min_overlap", min_overlap, "minimum frustum overlap between context and each target", Range::unit());
  v.field("min_valid_depth", min_valid_depth, "resample contexts whose valid-depth fraction is lower", Range::unit());
  v.field("max_attempts", max_attempts, "draws per tuple before giving up with an error", Range::at_least(1));
  v.section("augment", "training-time augmentation (off by default; never applied to validation tuples)", augment);
}

uint64_t mix_seed(uint64_t seed, uint64_t index) {
  uint64_t z = seed + 0x9E3779B97F4A7C15ull * (index + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

ViewTensors make_view_tensors(const LoadedFrame& frame, const std::string& name, int64_t width, int64_t height) {
  const int w = static_cast<int>(width), h = static_cast<int>(height);
  cv::Mat image = frame.image;
  cv::Mat depth = frame.has_depth() ? frame.depth.depth : cv::Mat();
  Intrinsics intr = frame.view.intr;
  fit_view(image, frame.has_depth() ? &depth : nullptr, intr, w, h);
  cv::Mat valid;
  if (frame.has_depth()) {
    frame.depth.valid.convertTo(valid, CV_32F);
    Intrinsics same = frame.view.intr;
    fit_view(valid, nullptr, same, w, h);  // area-averaged: 1 only where every source pixel was valid
  }
  ViewTensors out;
  out.image = image_to_tensor(image);
  if (frame.has_depth()) {
    out.depth = map_to_tensor(depth);
    // Area-averaged validity: a pixel is valid only if all its sources were; depth was sampled nearest.
    out.valid = (map_to_tensor(valid) > 0.999f).to(torch::kFloat32) * (out.depth > 0).to(torch::kFloat32);
    out.depth = out.depth * out.valid;
  } else {
    out.depth = torch::zeros({height, width});
    out.valid = torch::zeros({height, width});
  }
  View v{intr, frame.view.T_cw};
  out.camera = to_camera(v, torch::kFloat32);
  out.name = name;
  return out;
}

Batch collate(const std::vector<TupleSample>& samples) {
  ISPLAT_CHECK(!samples.empty(), "collate: empty batch");
  const size_t T = samples[0].targets.size();
  std::vector<torch::Tensor> ci, cd, cv, cK, cT, ti, td, tv, tK, tT;
  Batch b;
  for (const auto& s : samples) {
    ISPLAT_CHECK(s.targets.size() == T, "collate: tuples have different target counts");
    ci.push_back(s.context.image);
    cd.push_back(s.context.depth);
    cv.push_back(s.context.valid);
    cK.push_back(s.context.camera.K);
    cT.push_back(s.context.camera.T_cw);
    std::vector<torch::Tensor> i, d, v, k, t;
    for (const auto& x : s.targets) {
      i.push_back(x.image);
      d.push_back(x.depth);
      v.push_back(x.valid);
      k.push_back(x.camera.K);
      t.push_back(x.camera.T_cw);
    }
    ti.push_back(torch::stack(i));
    td.push_back(torch::stack(d));
    tv.push_back(torch::stack(v));
    tK.push_back(torch::stack(k));
    tT.push_back(torch::stack(t));
    b.names.push_back(s.context.name);
  }
  b.context_image = torch::stack(ci);
  b.context_depth = torch::stack(cd);
  b.context_valid = torch::stack(cv);
  b.context_K = torch::stack(cK);
  b.context_T = torch::stack(cT);
  b.target_image = torch::stack(ti);
  b.target_depth = torch::stack(td);
  b.target_valid = torch::stack(tv);
  b.target_K = torch::stack(tK);
  b.target_T = torch::stack(tT);
  return b;
}

TupleSampler::TupleSampler(std::vector<Sequence> sequences, TupleOptions options, uint64_t seed)
    : options_(options), seed_(seed) {
  for (auto& s : sequences)
    if (s.frames.size() >= 2) sequences_.push_back(std::move(s));
  for (const auto& s : sequences_) {
    cumulative_.push_back(total_frames_);
    total_frames_ += static_cast<int64_t>(s.frames.size());
  }
  ISPLAT_CHECK(total_frames_ > 0, "tuple sampler: no trajectory with at least 2 frames");
}

void TupleSampler::count_skip(const std::string& reason) const {
  std::lock_guard<std::mutex> lock(skip_mutex_);
  if (skips_[reason]++ < 5) log_warn("data: ", reason);
}

std::map<std::string, int64_t> TupleSampler::skip_counts() const {
  std::lock_guard<std::mutex> lock(skip_mutex_);
  return skips_;
}

TupleSample TupleSampler::sample(int64_t index) const {
  std::mt19937_64 rng(mix_seed(seed_, static_cast<uint64_t>(index)));
  for (int64_t attempt = 0; attempt < options_.max_attempts; ++attempt) {
    // Context: uniform over all frames.
    const int64_t g = std::uniform_int_distribution<int64_t>(0, total_frames_ - 1)(rng);
    const size_t s =
        static_cast<size_t>(std::upper_bound(cumulative_.begin(), cumulative_.end(), g) - cumulative_.begin() - 1);
    const Sequence& seq = sequences_[s];
    const int64_t c = g - cumulative_[s];
    LoadedFrame context;
    try {
      context = load_frame(seq, static_cast<size_t>(c));
    } catch (const Error& e) {
      count_skip(cat("skipping unreadable frame: ", e.what()));
      continue;
    }
    if (!context.has_depth()) {
      count_skip(cat("skipping context without depth: ", seq.frames[c].name));
      continue;
    }
    const auto pixels = static_cast<int64_t>(context.depth.valid.total());
    const double valid_fraction =
        static_cast<double>(pixels - context.depth.invalid_count) / static_cast<double>(pixels);
    if (valid_fraction < options_.min_valid_depth) {
      count_skip(
          cat("skipping context with ", static_cast<int>(valid_fraction * 100), "% valid depth: ", seq.frames[c].name));
      continue;
    }
    // Candidates within the window with enough overlap, sorted by baseline.
    struct Candidate {
      int64_t frame;
      double baseline, overlap;
    };
    std::vector<Candidate> cands;
    const int64_t n = static_cast<int64_t>(seq.frames.size());
    for (int64_t j = std::max<int64_t>(0, c - options_.window); j <= std::min(n - 1, c + options_.window); ++j) {
      if (j == c) continue;
      const double ov = frustum_overlap(context.view, context.depth, seq.frames[j].view);
      if (ov >= options_.min_overlap) cands.push_back({j, baseline(context.view, seq.frames[j].view), ov});
    }
    if (cands.empty()) {
      count_skip(cat("no target overlaps context ", seq.frames[c].name, " enough; redrawing"));
      continue;
    }
    std::sort(cands.begin(), cands.end(), [](const Candidate& a, const Candidate& b) {
      return a.baseline < b.baseline || (a.baseline == b.baseline && a.frame < b.frame);
    });
    // Spread of baselines: one target from each of T equal-count baseline strata.
    const int64_t T = options_.targets, m = static_cast<int64_t>(cands.size());
    std::vector<Candidate> chosen;
    for (int64_t k = 0; k < T; ++k) {
      const int64_t lo = k * m / T, hi = std::max(lo + 1, (k + 1) * m / T);
      chosen.push_back(cands[std::uniform_int_distribution<int64_t>(lo, std::min(hi, m) - 1)(rng)]);
    }
    TupleSample out;
    try {
      out.context = make_view_tensors(context, seq.frames[c].name, options_.width, options_.height);
      for (const auto& t : chosen) {
        LoadedFrame tf = load_frame(seq, static_cast<size_t>(t.frame));
        out.targets.push_back(make_view_tensors(tf, seq.frames[t.frame].name, options_.width, options_.height));
        out.baselines.push_back(t.baseline);
        out.overlaps.push_back(t.overlap);
      }
    } catch (const Error& e) {
      count_skip(cat("skipping unreadable frame: ", e.what()));
      continue;
    }
    augment_tuple(out, options_.augment, mix_seed(seed_ ^ 0xA5A5A5A5A5A5A5A5ull, static_cast<uint64_t>(index)));
    return out;
  }
  fail("tuple sampler: ", options_.max_attempts, " draws for tuple ", index,
       " all failed (unreadable frames, too little valid depth or no overlapping targets); see warnings above");
}

}  // namespace isplat
