// Tuple sampler and batch loader: determinism, target overlap and baseline spread, resizing with
// intrinsics, skipped unreadable frames, and prefetching workers giving the same batches.
#include <catch2/catch.hpp>

#include <torch/torch.h>
#include <filesystem>

#include "data/hypersim.h"
#include "data/loader.h"
#include "data/tuples.h"
#include "support/test_util.h"
#include "support/tiny_dataset.h"

using namespace isplat;
namespace fs = std::filesystem;

namespace {
std::vector<Sequence> tiny_sequences(const GenerateOptions& g) {
  HypersimOptions h;
  h.root = generated_hypersim_root(g.out);
  h.split = "all";
  return read_hypersim(h).sequences;
}
TupleOptions small_tuples() {
  TupleOptions t;
  t.width = 48;
  t.height = 32;
  t.targets = 3;
  t.window = 6;
  t.min_overlap = 0.3;
  return t;
}
bool same(const TupleSample& a, const TupleSample& b) {
  if (a.context.name != b.context.name || a.targets.size() != b.targets.size()) return false;
  for (size_t i = 0; i < a.targets.size(); ++i)
    if (a.targets[i].name != b.targets[i].name || !torch::equal(a.targets[i].image, b.targets[i].image)) return false;
  return torch::equal(a.context.image, b.context.image) && torch::equal(a.context.depth, b.context.depth);
}
}  // namespace

TEST_CASE("tuples: same seed and index give the same tuple", "[data][tuples]") {
  const auto g = test::make_tiny_dataset("tuples_det", 12);
  TupleSampler s1(tiny_sequences(g), small_tuples(), 42), s2(tiny_sequences(g), small_tuples(), 42);
  CHECK(same(s1.sample(3), s2.sample(3)));
  bool any_differs = false;
  for (int i = 0; i < 6 && !any_differs; ++i) any_differs = !same(s1.sample(i), s1.sample(i + 1));
  CHECK(any_differs);
  TupleSampler s3(tiny_sequences(g), small_tuples(), 43);
  bool seed_matters = false;
  for (int i = 0; i < 6 && !seed_matters; ++i) seed_matters = !same(s1.sample(i), s3.sample(i));
  CHECK(seed_matters);
}

TEST_CASE("tuples: targets overlap the context and spread over baselines", "[data][tuples]") {
  const auto g = test::make_tiny_dataset("tuples_targets", 12);
  const auto opts = small_tuples();
  TupleSampler sampler(tiny_sequences(g), opts, 7);
  for (int i = 0; i < 5; ++i) {
    const auto t = sampler.sample(i);
    REQUIRE(t.targets.size() == 3);
    for (double ov : t.overlaps) CHECK(ov >= opts.min_overlap);
    CHECK(t.baselines[0] <= t.baselines[1]);  // one target per baseline stratum
    CHECK(t.baselines[1] <= t.baselines[2]);
    CHECK(t.context.image.sizes() == torch::IntArrayRef({3, 32, 48}));
    CHECK(t.context.depth.sizes() == torch::IntArrayRef({32, 48}));
    CHECK(t.context.camera.K.sizes() == torch::IntArrayRef({3, 3}));
    CHECK(torch::isfinite(t.context.depth).all().item<bool>());
    CHECK(((t.context.depth > 0) == (t.context.valid > 0.5)).all().item<bool>());
    for (const auto& tv : t.targets) CHECK(tv.name.substr(0, 10) == t.context.name.substr(0, 10));  // same scene
  }
}

TEST_CASE("tuples: intrinsics follow the centre crop and resize", "[data][tuples]") {
  const auto g = test::make_tiny_dataset("tuples_K", 8);
  auto seqs = tiny_sequences(g);
  const Sequence& seq = seqs[0];  // 64x48, not tilt-shift
  const LoadedFrame f = load_frame(seq, 0);
  const ViewTensors v = make_view_tensors(f, "x", 48, 32);
  // 4:3 -> 3:2 keeps a centred 64x43 window (rows 2..44), then scales it to 48x32.
  const double sx = 48.0 / 64.0, sy = 32.0 / 43.0;
  CHECK(v.camera.K[0][0].item<double>() == Approx(f.view.intr.fx * sx).epsilon(1e-5));
  CHECK(v.camera.K[1][1].item<double>() == Approx(f.view.intr.fy * sy).epsilon(1e-5));
  CHECK(v.camera.K[0][2].item<double>() == Approx(f.view.intr.cx * sx).epsilon(1e-5));
  CHECK(v.camera.K[1][2].item<double>() == Approx((f.view.intr.cy - 2.0) * sy).epsilon(1e-5));
}

TEST_CASE("tuples: unreadable frames are skipped with a count", "[data][tuples]") {
  const auto g = test::make_tiny_dataset("tuples_skip", 10);
  auto seqs = tiny_sequences(g);
  // Corrupt every image of the first trajectory after the reader has listed it.
  for (const auto& f : seqs[0].frames) test::write_bytes(f.image_path, "not a jpeg");
  TupleSampler sampler(seqs, small_tuples(), 1);
  int64_t ok = 0;
  for (int i = 0; i < 6; ++i) ok += static_cast<int64_t>(sampler.sample(i).targets.size() == 3);
  CHECK(ok == 6);
  const auto skips = sampler.skip_counts();
  int64_t unreadable = 0;
  for (const auto& [reason, n] : skips)
    if (reason.find("unreadable") != std::string::npos) unreadable += n;
  CHECK(unreadable > 0);
}

TEST_CASE("loader: worker threads give the same batches in the same order", "[data][loader]") {
  const auto g = test::make_tiny_dataset("loader", 10);
  TupleSampler sampler(tiny_sequences(g), small_tuples(), 5);
  std::vector<Batch> sync_batches;
  {
    BatchLoader sync(sampler, 2, 0, 1);
    for (int k = 0; k < 4; ++k) sync_batches.push_back(sync.next());
  }
  BatchLoader threaded(sampler, 2, 2, 3);
  for (int k = 0; k < 4; ++k) {
    const Batch b = threaded.next();
    CHECK(b.names == sync_batches[k].names);
    CHECK(torch::equal(b.target_image, sync_batches[k].target_image));
    CHECK(b.target_image.sizes() == torch::IntArrayRef({2, 3, 3, 32, 48}));
    CHECK(b.target_K.sizes() == torch::IntArrayRef({2, 3, 3, 3}));
  }
  BatchLoader resumed(sampler, 2, 1, 2, 2);  // a resumed run starts at batch 2
  CHECK(resumed.next().names == sync_batches[2].names);
}
