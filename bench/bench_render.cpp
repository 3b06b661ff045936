// Renderer benchmark: base Gaussians from a generated room (generator + sampler + composer), forward and
// forward+backward medians, per-phase times, intersections per second and peak memory at three sizes plus a
// large-splats variant.
#include <ATen/Parallel.h>
#include <torch/torch.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "core/app.h"
#include "core/args.h"
#include "core/error.h"
#include "core/runtime.h"
#include "data/synth/builder.h"
#include "data/synth/render.h"
#include "decoder/composer.h"
#include "geometry/camera.h"
#include "geometry/camera_torch.h"
#include "io/safetensors.h"
#include "io/tensor_image.h"
#include "render/kernels.h"
#include "render/render.h"
#include "sampler/base_gaussians.h"
#include "sampler/sampler.h"

using namespace isplat;

namespace {

// ---- The scene: the project's own generator, sampler and base Gaussians ----

struct Scene {
  Gaussians gaussians;
  Camera target;
};

// A generated room (data/synth), rendered from the first pose of a generated trajectory; supports from the
// project's area sampler on its planar depth, composed into base Gaussians with zero updates (DESIGN §3).
// On top, the kind of spread a decoder adds: per-axis scale jitter exp(0.25·n), small rotations, opacity
// sigmoid(1.2·n). Rendered from the trajectory's next pose (0.15 m on). `scale_factor` > 1: large splats.
Scene make_scene(int64_t n, int W, int H, double scale_factor, uint64_t seed) {
  const synth::Scene room = synth::build_room(seed);
  const auto poses = synth::make_trajectory(room, 2, seed, 0.15, 0.15);
  const Intrinsics intr = Intrinsics::from_hfov(65.0 * M_PI / 180.0, W, H);
  const synth::RenderedFrame frame = synth::render_frame(room, synth::pinhole_ray_camera(poses[0], intr), 1);
  auto depth = map_to_tensor(frame.planar);
  const auto valid = torch::isfinite(depth) & (depth > 0);
  depth = torch::where(valid, depth, torch::zeros_like(depth));
  const auto image = torch::pow(image_to_tensor(frame.radiance).clamp(0, 1), 1.0 / 2.2);  // display sRGB
  auto view_of = [&](const synth::CameraPose& c) {
    View v;
    v.intr = intr;
    v.T_cw = invert_pose(make_pose(c.R_wc, c.center));
    return v;
  };
  const Camera source = to_camera(view_of(poses[0]), torch::kFloat32);
  SamplerOptions so;
  so.budget = n;
  const Supports supports = sample_supports(depth, valid, source.K, image, so, seed);
  const BaseGaussians base = make_base_gaussians(supports);
  Gaussians g = compose(base, torch::zeros({supports.count(), kDeltaDim}), source.K, source.T_cw, ComposerOptions{});
  torch::manual_seed(seed);
  const auto jitter = torch::randn({n, 7}, torch::kFloat32);
  g.scales = (g.scales * scale_factor * torch::exp(0.25 * jitter.narrow(1, 0, 3))).contiguous();
  g.quats = torch::cat({torch::ones({n, 1}), 0.3 * jitter.narrow(1, 3, 3)}, 1).contiguous();
  g.opacities = torch::sigmoid(1.2 * jitter.select(1, 6)).contiguous();
  for (torch::Tensor* t : {&g.means, &g.colors}) *t = t->to(torch::kFloat32).contiguous();
  return {g, to_camera(view_of(poses[1]), torch::kFloat32)};
}

// ---- Measurement helpers ----

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// CPU time of the whole process (all threads), immune to waiting for a busy machine.
double cpu_ms() {
  timespec ts;
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// The statistic of the timed runs (--stat): the median, or the minimum, which a machine shared with other
// tenants disturbs least (a run is only ever slowed down by them).
bool g_use_min = false;
// --save-scene: the folder each case's Gaussians and camera are written to (bench/bench_python_render.py reads them).
std::string g_save_scene;
double stat(const std::vector<double>& v) {
  return g_use_min ? (v.empty() ? 0.0 : *std::min_element(v.begin(), v.end())) : median(v);
}

// The resident size now: reset_peak_memory() makes the peak the current size.
double resident_mb() {
  reset_peak_memory();
  return peak_memory_mb();
}

double mb(const torch::Tensor& t) {
  return t.defined() ? double(t.numel() * t.element_size()) / (1 << 20) : 0.0;
}

struct Case {
  std::string name;
  int64_t n;
  int W, H;
  double scale_factor;
  int fwd_runs, bwd_runs;
};

void run(const Case& cs) {
  const double t_build = now_ms();
  const Scene scene = make_scene(cs.n, cs.W, cs.H, cs.scale_factor, 1234);
  const Gaussians& g = scene.gaussians;
  const Camera& cam = scene.target;
  const double build_ms = now_ms() - t_build;
  if (!g_save_scene.empty()) {
    std::string file = cs.name;
    std::replace(file.begin(), file.end(), ' ', '_');
    write_safetensors(g_save_scene + "/" + file + ".safetensors",
                      {{"means", g.means},
                       {"quats", g.quats},
                       {"scales", g.scales},
                       {"opacities", g.opacities},
                       {"colors", g.colors},
                       {"K", cam.K},
                       {"T_cw", cam.T_cw},
                       {"size", torch::tensor({int64_t(cs.W), int64_t(cs.H)})}});
  }
  const double rss0 = resident_mb();  // also resets the peak, so each case reports its own

  // Forward + backward as the trainer renders (no loss reads the normal map): an L1 loss on rgb plus light depth and
  // alpha terms, or (rgb_only) the L1 loss alone without the depth map, as the recipe trains.
  Gaussians p = g;
  for (torch::Tensor* t : {&p.means, &p.scales, &p.quats, &p.colors, &p.opacities})
    *t = t->clone().requires_grad_(true);
  const auto target = torch::full({3, cs.H, cs.W}, 0.5f);
  auto forward_backward = [&](bool rgb_only) {
    RenderMaps training;
    training.normals = false;
    training.depth_map = !rgb_only;
    for (torch::Tensor* t : {&p.means, &p.scales, &p.quats, &p.colors, &p.opacities})
      t->mutable_grad() = torch::Tensor();
    const double t0 = now_ms();
    const RenderOutput out = render(p, cam, {}, training);
    auto loss = (out.rgb - target).abs().mean();
    if (!rgb_only) loss = loss + 0.01 * out.depth.mean() + 0.1 * out.alpha.mean();
    loss.backward();
    return now_ms() - t0;
  };

  // The first render and the first forward + backward of this case: in a fresh process (--only NAME), every buffer
  // is new memory (for the forward + backward, the backward's: its forward follows the first render).
  double first = now_ms();
  render(g, cam);
  first = now_ms() - first;
  const double first_fb = cs.bwd_runs > 0 ? forward_backward(false) : NAN;  // its backward is the process's first
  for (torch::Tensor* t : {&p.means, &p.scales, &p.quats, &p.colors, &p.opacities}) t->mutable_grad() = torch::Tensor();
  reset_peak_memory();  // so peakF stays the forward runs' peak, as before this column

  // Per-phase times through the kernels (the same calls render() makes), and the buffer sizes.
  const splat::CameraParams cp = splat::camera_params(cam.K, cam.T_cw, cs.W, cs.H);
  const double bg[3] = {0, 0, 0};
  std::vector<double> t_proj, t_bin, t_rast, t_rbwd, t_pbwd, c_fwd, c_bwd;
  int64_t isects = 0, visible = 0;
  double buffers_fwd = 0, buffers_bwd = 0;
  for (int r = 0; r < std::max(1, cs.fwd_runs / 2); ++r) {
    double c0 = cpu_ms(), t0 = now_ms();
    const auto proj = splat::project_fwd(g.means, g.scales, g.quats, g.colors, g.opacities, cp, {});
    double t1 = now_ms();
    const auto bins = splat::bin_tiles(proj, cp);
    double t2 = now_ms();
    const auto ras = splat::rasterize_fwd(proj.packed, bins, cp, bg, {true, false, true});  // hits for the backward
    double t3 = now_ms(), c3 = cpu_ms();
    const auto ones = torch::ones({3, cs.H, cs.W}), one = torch::ones({1, cs.H, cs.W});
    const auto grad2d =
        splat::rasterize_bwd(proj.packed, bins, cp, bg, ras.final_T, ras.n_contrib, ones, one, one, ras.group_hits);
    double t4 = now_ms();
    const auto pg = splat::project_bwd(g.means, g.scales, g.quats, g.opacities, cp, {}, grad2d);
    double t5 = now_ms(), c5 = cpu_ms();
    c_fwd.push_back(c3 - c0), c_bwd.push_back(c5 - c3);
    t_proj.push_back(t1 - t0), t_bin.push_back(t2 - t1), t_rast.push_back(t3 - t2);
    t_rbwd.push_back(t4 - t3), t_pbwd.push_back(t5 - t4);
    isects = bins.intersections();
    visible = (proj.rects.select(1, 2) > proj.rects.select(1, 0)).sum().item<int64_t>();
    // Renderer-owned buffers: records, rects, sort keys/ids (2 copies each), tile lists, output images.
    buffers_fwd = mb(proj.packed) + mb(proj.rects) + 4 * double(visible) * 8 / (1 << 20) + mb(bins.isect_ids) +
                  mb(bins.tile_offsets) + mb(ras.rgb) * 3 + mb(ras.final_T) + mb(ras.n_contrib);
    buffers_bwd = buffers_fwd + double(isects) * splat::kGrad2d * 4 / (1 << 20) + mb(grad2d) + mb(pg.means) +
                  mb(pg.scales) + mb(pg.quats) + mb(pg.opacities) + mb(ones) + 2 * mb(one);
  }

  // Forward through the public API (no autograd state), and in alternate runs with the median depth (the evaluator's
  // render under scoring.crack_depth = median).
  std::vector<double> fwd, fwd_median;
  RenderMaps with_median;
  with_median.median_depth = true;
  for (int r = 0; r < 2 * cs.fwd_runs; ++r) {
    const double t0 = now_ms();
    const RenderOutput out = render(g, cam, {}, r % 2 == 1 ? with_median : RenderMaps{});
    (r % 2 == 1 ? fwd_median : fwd).push_back(now_ms() - t0);
  }
  const double peak_fwd = peak_memory_mb();

  // Forward + backward as the trainer renders (no loss reads the normal map), in alternate runs: an L1 loss on rgb
  // plus light depth and alpha terms (fb), and the L1 loss alone without the depth map (fb_rgb, the recipe's losses).
  std::vector<double> fb, fb_rgb;
  for (int r = 0; r < 2 * cs.bwd_runs; ++r) {
    const bool rgb_only = r % 2 == 1;
    (rgb_only ? fb_rgb : fb).push_back(forward_backward(rgb_only));
  }
  const double peak_all = peak_memory_mb();

  const double f = stat(fwd), b = stat(fb), b_rgb = stat(fb_rgb), f_median = stat(fwd_median);
  std::cout << std::fixed << std::setprecision(1);
  std::cout << "| " << std::left << std::setw(20) << cs.name << std::right << " | " << std::setw(8) << cs.n << " | "
            << std::setw(9) << (std::to_string(cs.W) + "x" + std::to_string(cs.H)) << " | " << std::setw(8) << visible
            << " | " << std::setw(9) << isects << " | " << std::setw(8) << first << " | " << std::setw(8) << f << " | "
            << std::setw(8) << (cs.bwd_runs ? b : NAN) << " | " << std::setw(7) << std::setprecision(1)
            << double(isects) / f / 1e3 << " | " << std::setw(6) << stat(t_proj) << " | " << std::setw(6) << stat(t_bin)
            << " | " << std::setw(7) << stat(t_rast) << " | " << std::setw(7) << stat(t_rbwd) << " | " << std::setw(6)
            << stat(t_pbwd) << " | " << std::setw(7) << peak_fwd << " | " << std::setw(7)
            << (cs.bwd_runs ? peak_all : NAN) << " | " << std::setw(6) << rss0 << " | " << std::setw(6) << buffers_fwd
            << " | " << std::setw(6) << buffers_bwd << " | " << std::setw(6) << build_ms / 1000 << " | " << std::setw(6)
            << stat(c_fwd) << " | " << std::setw(6) << stat(c_bwd) << " | " << std::setw(8)
            << (cs.bwd_runs ? b_rgb : NAN) << " | " << std::setw(8) << f_median << " | " << std::setw(9) << first_fb
            << " |" << std::endl;
}

}  // namespace

int main(int argc, char** argv) {
  return run_main("bench_render", [&] {
    int64_t threads = 0, runs_scale = 1;
    bool quick = false, huge_large = false;
    std::string only, simd = "best", statistic = "median";
    ArgParser parser("bench_render",
                     "Times the CPU splatting renderer on Gaussians from a generated room (the project's generator, "
                     "sampler and base Gaussians).");
    parser.option("--threads", threads, "threads (0 = all cores)");
    parser.option("--runs-scale", runs_scale, "multiply the number of timed runs");
    parser.flag("--quick", quick, "only the two smaller sizes");
    parser.flag("--large-1.5m", huge_large, "also run the large-splats variant at 1.5M");
    parser.option("--only", only, "run only the case with this name (e.g. 100k)", "NAME");
    parser.option("--simd", simd, "pixel loops and projection: best (what the CPU has), avx512, avx2 or portable",
                  "LEVEL");
    parser.option("--stat", statistic, "statistic of the timed runs: median, or min (steadier on a shared machine)",
                  "STAT");
    parser.option("--save-scene", g_save_scene,
                  "write each case's Gaussians and camera to DIR/<case>.safetensors (for bench_python_render.py)",
                  "DIR");
    if (!parser.parse(argc, argv)) return 0;
    ISPLAT_CHECK(statistic == "median" || statistic == "min", "bench_render: --stat: '", statistic,
                 "' is not median or min");
    g_use_min = statistic == "min";
    const std::vector<std::string> levels = {"portable", "avx2", "avx512"};
    if (simd != "best") {
      const auto it = std::find(levels.begin(), levels.end(), simd);
      ISPLAT_CHECK(it != levels.end(), "bench_render: --simd: '", simd, "' is not best, avx512, avx2 or portable");
      const auto wanted = splat::Simd(it - levels.begin());
      splat::set_simd_level(wanted);
      ISPLAT_CHECK(splat::simd_level() == wanted, "bench_render: --simd: this CPU has no ", simd,
                   " (best: ", splat::simd_name(splat::simd_supported()), ")");
    }
    const int used = configure_threads(threads);
    std::cout
        << "bench_render: " << used << " threads, " << splat::simd_name(splat::simd_level()) << " kernels, "
        << statistic << " of timed runs (ms); float32; times exclude scene building\n"
        << "freed memory is kept for reuse (as in every executable); MALLOC_MMAP_MAX_=65536 in the environment "
           "gives glibc's default instead\n"
        << "cols: first / first f+b = the case's first render() and first forward+backward (cold in a fresh "
           "process: --only NAME); fwd = render(); fwd+bwd = "
           "render without the normal map (as in training) + L1 loss with light depth and alpha terms + backward "
           "(f+b rgb: the L1 loss alone and no depth map, as the recipe trains);\n      fwd med = fwd with the median "
           "depth too (the evaluator's render under scoring.crack_depth = median); Misect/s = "
           "intersections per second of fwd;\n      proj/bin/rast/rbwd/pbwd = phases (project, tile binning, rasterize "
           "fwd, rasterize bwd, "
           "project bwd);\n      peakF/peakFB = VmHWM (MB, process peak reset before the case) after the fwd "
           "runs (fwd med's included) / after fwd+bwd;\n      rss0 = VmRSS at the start of the case (scene inputs "
           "included); bufF/bufB "
           "= renderer's own buffers (MB);\n      cpuF/cpuB = process CPU ms of the kernel phases fwd (proj+bin+rast) "
           "/ bwd (rbwd+pbwd)\n\n";
    std::cout
        << "| case                 |        N |     image |  visible |    isects | first ms |   fwd ms | f+b ms   | "
           "Misect/s "
           "|  proj |   bin |    rast |    rbwd |  pbwd |   peakF |  peakFB |   rss0 |   bufF |   bufB | build s | "
           "cpuF   | cpuB   | f+b rgb  | fwd med  | first f+b |\n";
    const int k = int(std::max<int64_t>(1, runs_scale));
    std::vector<Case> cases = {{"20k", 20000, 256, 192, 1.0, 11 * k, 11 * k},
                               {"20k large splats", 20000, 256, 192, 3.0, 11 * k, 11 * k},
                               {"100k", 100000, 512, 384, 1.0, 9 * k, 9 * k},
                               {"100k large splats", 100000, 512, 384, 3.0, 7 * k, 7 * k}};
    if (!quick || !only.empty()) {
      cases.push_back({"1.5M", 1500000, 1536, 1024, 1.0, 5 * k, 3 * k});
      if (huge_large || !only.empty()) cases.push_back({"1.5M large splats", 1500000, 1536, 1024, 3.0, 3 * k, 1 * k});
    }
    for (const Case& c : cases)
      if (only.empty() || c.name == only) run(c);
    return 0;
  });
}
