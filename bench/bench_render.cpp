// Renderer benchmark: Gaussians from a synthetic room's depth map, forward and forward+backward medians,
// per-phase times, intersections per second and peak memory at three sizes plus a large-splats variant.
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

#include "core/args.h"
#include "core/error.h"
#include "core/runtime.h"
#include "geometry/camera.h"
#include "geometry/camera_torch.h"
#include "render/kernels.h"
#include "render/render.h"

using namespace isplat;
using Eigen::Vector3d;

namespace {

// ---- A synthetic room: an inside-out box with two solid boxes (table, cabinet) and textured faces ----

struct Hit {
  double t = 0;
  Vector3d normal, color;
};

struct Box {
  Vector3d lo, hi, color;
};

Vector3d texture(const Vector3d& p, const Vector3d& base) {
  const double checker = ((int(std::floor(p.x() * 3)) + int(std::floor(p.y() * 3)) + int(std::floor(p.z() * 3))) & 1);
  const double stripes = 0.5 + 0.5 * std::sin(17.0 * (p.x() + 0.7 * p.z()));
  return (base * (0.7 + 0.2 * checker + 0.1 * stripes)).cwiseMin(1.0);
}

struct Room {
  Box shell{{-2.5, -1.3, -1.0}, {2.5, 1.5, 6.0}, {0.75, 0.7, 0.6}};
  std::vector<Box> solids{{{-1.2, 0.7, 2.4}, {0.3, 1.5, 3.4}, {0.55, 0.35, 0.2}},
                          {{1.1, -0.6, 3.6}, {2.5, 1.5, 5.0}, {0.3, 0.45, 0.7}},
                          {{-2.5, -0.2, 4.2}, {-1.6, 1.5, 6.0}, {0.8, 0.8, 0.75}}};

  bool cast(const Vector3d& o, const Vector3d& d, Hit& hit) const {
    // Exit of the shell.
    double t_exit = 1e30;
    int axis = 0;
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0) continue;
      const double t = ((d[a] > 0 ? shell.hi[a] : shell.lo[a]) - o[a]) / d[a];
      if (t < t_exit) t_exit = t, axis = a;
    }
    hit.t = t_exit;
    hit.normal = Vector3d::Zero();
    hit.normal[axis] = d[axis] > 0 ? -1 : 1;
    Vector3d base = shell.color;
    if (axis == 1) base = d[1] > 0 ? Vector3d(0.45, 0.35, 0.3) : Vector3d(0.9, 0.9, 0.88);  // floor, ceiling
    // Entries of the solids.
    for (const Box& b : solids) {
      double t0 = -1e30, t1 = 1e30;
      int ax = 0;
      for (int a = 0; a < 3; ++a) {
        if (d[a] == 0) {
          if (o[a] < b.lo[a] || o[a] > b.hi[a]) t0 = 1e30;
          continue;
        }
        double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
        if (ta > tb) std::swap(ta, tb);
        if (ta > t0) t0 = ta, ax = a;
        t1 = std::min(t1, tb);
      }
      if (t0 <= t1 && t0 > 1e-6 && t0 < hit.t) {
        hit.t = t0;
        hit.normal = Vector3d::Zero();
        hit.normal[ax] = d[ax] > 0 ? -1 : 1;
        base = b.color;
      }
    }
    hit.color = texture(o + hit.t * d, base);
    return hit.t < 1e29;
  }
};

View make_view(int W, int H, double yaw_deg, double x) {
  View v;
  v.intr = Intrinsics::from_hfov(65.0 * M_PI / 180.0, W, H);
  const Eigen::Matrix3d R_wc = (Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Vector3d::UnitY()) *
                                Eigen::AngleAxisd(-8.0 * M_PI / 180.0, Vector3d::UnitX()))
                                   .toRotationMatrix();
  const Vector3d C(x, 0.1, 0.0);
  v.T_cw = make_pose(R_wc.transpose(), -R_wc.transpose() * C);
  return v;
}

// DESIGN §3 sampler in miniature: supports stratified by 3D surface area over the source view's depth map
// (per-pixel area z²·cosφ/(fx·fy·cosθ)), placed at sub-pixel R2 positions and ray cast; being stratified by
// area, each stands for total area / N, so the base scale is sqrt(total area / N) (isotropic), base opacity
// 0.5. On top, the kind of spread a decoder adds: per-axis scale jitter exp(0.25·n), small rotations, opacity
// sigmoid(1.2·n). Rendered from a nearby target view (0.15 m, 3°). `scale_factor` > 1: large-splats variant.
Gaussians make_scene(int64_t n, int W, int H, double scale_factor, uint64_t seed) {
  const Room room;
  const View src = make_view(W, H, 0.0, 0.0);
  const Eigen::Matrix3d R_wc = src.T_cw.topLeftCorner<3, 3>().transpose();
  const Vector3d C = camera_center(src.T_cw);
  const Intrinsics& K = src.intr;
  std::vector<double> cum(size_t(W) * H + 1, 0.0);
  for (int i = 0; i < H; ++i)
    for (int j = 0; j < W; ++j) {
      const Vector3d r = K.ray(j + 0.5, i + 0.5);
      const Vector3d d = R_wc * r;
      Hit h;
      double area = 0;
      if (room.cast(C, d, h)) {
        const double z = h.t;  // r has unit z, so the ray parameter is the planar depth
        const double cos_phi = 1.0 / r.norm(), cos_theta = std::max(0.1, std::abs(h.normal.dot(d.normalized())));
        area = z * z * cos_phi / (K.fx * K.fy * cos_theta);
      }
      cum[size_t(i) * W + j + 1] = cum[size_t(i) * W + j] + area;
    }
  const double total = cum.back(), base_scale = std::sqrt(total / double(n));
  torch::manual_seed(seed);
  const auto jitter = torch::randn({n, 8}, torch::kFloat64);
  const double* jr = jitter.data_ptr<double>();
  auto means = torch::empty({n, 3}, torch::kFloat32), scales = torch::empty({n, 3}, torch::kFloat32);
  auto quats = torch::empty({n, 4}, torch::kFloat32), colors = torch::empty({n, 3}, torch::kFloat32);
  auto opac = torch::empty({n}, torch::kFloat32);
  float *m = means.data_ptr<float>(), *s = scales.data_ptr<float>(), *q = quats.data_ptr<float>();
  float *c = colors.data_ptr<float>(), *o = opac.data_ptr<float>();
  size_t pix = 0;
  const double g1 = 0.7548776662466927, g2 = 0.5698402909980532;  // R2 low-discrepancy sequence
  for (int64_t k = 0; k < n; ++k) {
    const double target = (double(k) + 0.5) / double(n) * total;  // stratified over the cumulative area
    while (pix + 1 < cum.size() - 1 && cum[pix + 1] <= target) ++pix;
    const double fu = std::fmod(0.5 + g1 * double(k), 1.0), fv = std::fmod(0.5 + g2 * double(k), 1.0);
    const double u = double(pix % W) + fu, v = double(pix / W) + fv;
    const Vector3d d = R_wc * K.ray(u, v);
    Hit h;
    if (!room.cast(C, d, h)) h.t = 1.0, h.color = Vector3d(0.5, 0.5, 0.5);
    const Vector3d p = C + h.t * d;
    const double* jk = jr + 8 * k;
    for (int a = 0; a < 3; ++a) {
      m[3 * k + a] = float(p[a]);
      s[3 * k + a] = float(base_scale * scale_factor * std::exp(0.25 * jk[a]));
      c[3 * k + a] = float(std::pow(std::clamp(h.color[a], 0.01, 0.99), 2.2));  // linear RGB
    }
    const double qn = std::sqrt(1 + 0.09 * (jk[3] * jk[3] + jk[4] * jk[4] + jk[5] * jk[5]));
    q[4 * k] = float(1 / qn), q[4 * k + 1] = float(0.3 * jk[3] / qn), q[4 * k + 2] = float(0.3 * jk[4] / qn);
    q[4 * k + 3] = float(0.3 * jk[5] / qn);
    o[k] = float(1.0 / (1.0 + std::exp(-(0.0 + 1.2 * jk[6]))));
  }
  return {means, scales, quats, colors, opac};
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

// kB fields of /proc/self/status, e.g. "VmHWM" (peak resident set) or "VmRSS".
double status_mb(const std::string& key) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(key + ":", 0) == 0) return std::stod(line.substr(key.size() + 1)) / 1024.0;
  return 0;
}

// Resets the peak-RSS counter (Linux >= 4.0), so each case reports its own peak.
void reset_peak() {
  std::ofstream("/proc/self/clear_refs") << "5";
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
  const Gaussians g = make_scene(cs.n, cs.W, cs.H, cs.scale_factor, 1234);
  const Camera cam = to_camera(make_view(cs.W, cs.H, 3.0, 0.15), torch::kFloat32);  // a nearby target view
  const double build_ms = now_ms() - t_build;
  reset_peak();
  const double rss0 = status_mb("VmRSS");

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
    const auto ras = splat::rasterize_fwd(proj.packed, bins, cp, bg);
    double t3 = now_ms(), c3 = cpu_ms();
    const auto ones = torch::ones({3, cs.H, cs.W}), one = torch::ones({1, cs.H, cs.W});
    const auto grad2d = splat::rasterize_bwd(proj.packed, bins, cp, bg, ras.final_T, ras.n_contrib, ones, one, one);
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

  // Forward through the public API (no autograd state).
  std::vector<double> fwd;
  for (int r = 0; r < cs.fwd_runs; ++r) {
    const double t0 = now_ms();
    const RenderOutput out = render(g, cam);
    fwd.push_back(now_ms() - t0);
  }
  const double peak_fwd = status_mb("VmHWM");

  // Forward + backward of an L1 loss on rgb plus light depth and alpha terms.
  std::vector<double> fb;
  if (cs.bwd_runs > 0) {
    Gaussians p = g;
    for (torch::Tensor* t : {&p.means, &p.scales, &p.quats, &p.colors, &p.opacities})
      *t = t->clone().requires_grad_(true);
    const auto target = torch::full({3, cs.H, cs.W}, 0.5f);
    for (int r = 0; r < cs.bwd_runs; ++r) {
      for (torch::Tensor* t : {&p.means, &p.scales, &p.quats, &p.colors, &p.opacities})
        t->mutable_grad() = torch::Tensor();
      const double t0 = now_ms();
      const RenderOutput out = render(p, cam);
      const auto loss = (out.rgb - target).abs().mean() + 0.01 * out.depth.mean() + 0.1 * out.alpha.mean();
      loss.backward();
      fb.push_back(now_ms() - t0);
    }
  }
  const double peak_all = status_mb("VmHWM");

  const double f = median(fwd), b = median(fb);
  std::cout << std::fixed << std::setprecision(1);
  std::cout << "| " << std::left << std::setw(20) << cs.name << std::right << " | " << std::setw(8) << cs.n << " | "
            << std::setw(9) << (std::to_string(cs.W) + "x" + std::to_string(cs.H)) << " | " << std::setw(8) << visible
            << " | " << std::setw(9) << isects << " | " << std::setw(8) << f << " | " << std::setw(8)
            << (cs.bwd_runs ? b : NAN) << " | " << std::setw(7) << std::setprecision(1) << double(isects) / f / 1e3
            << " | " << std::setw(6) << median(t_proj) << " | " << std::setw(6) << median(t_bin) << " | "
            << std::setw(7) << median(t_rast) << " | " << std::setw(7) << median(t_rbwd) << " | " << std::setw(6)
            << median(t_pbwd) << " | " << std::setw(7) << peak_fwd << " | " << std::setw(7)
            << (cs.bwd_runs ? peak_all : NAN) << " | " << std::setw(6) << rss0 << " | " << std::setw(6) << buffers_fwd
            << " | " << std::setw(6) << buffers_bwd << " | " << std::setw(6) << build_ms / 1000 << " | " << std::setw(6)
            << median(c_fwd) << " | " << std::setw(6) << median(c_bwd) << " |" << std::endl;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    int64_t threads = 0, runs_scale = 1;
    bool quick = false, huge_large = false;
    std::string only;
    ArgParser parser("bench_render", "Times the CPU splatting renderer on Gaussians from a synthetic room.");
    parser.option("--threads", threads, "threads (0 = all cores)");
    parser.option("--runs-scale", runs_scale, "multiply the number of timed runs");
    parser.flag("--quick", quick, "only the two smaller sizes");
    parser.flag("--large-1.5m", huge_large, "also run the large-splats variant at 1.5M");
    parser.option("--only", only, "run only the case with this name (e.g. 100k)", "NAME");
    if (!parser.parse(argc, argv)) return 0;
    const int used = configure_threads(threads);
    std::cout
        << "bench_render: " << used << " threads, median of timed runs (ms); float32; times exclude scene building\n"
        << "cols: fwd = render(); fwd+bwd = render + L1 loss + backward; Misect/s = intersections per second of "
           "fwd;\n      proj/bin/rast/rbwd/pbwd = phases (project, tile binning, rasterize fwd, rasterize bwd, "
           "project bwd);\n      peakF/peakFB = VmHWM (MB, process peak reset before the case) after the fwd "
           "runs / after fwd+bwd;\n      rss0 = VmRSS at the start of the case (scene inputs included); bufF/bufB "
           "= renderer's own buffers (MB);\n      cpuF/cpuB = process CPU ms of the kernel phases fwd (proj+bin+rast) "
           "/ bwd (rbwd+pbwd)\n\n";
    std::cout
        << "| case                 |        N |     image |  visible |    isects |   fwd ms | f+b ms   | Misect/s "
           "|  proj |   bin |    rast |    rbwd |  pbwd |   peakF |  peakFB |   rss0 |   bufF |   bufB | build s | "
           "cpuF   | cpuB   |\n";
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
  } catch (const std::exception& e) {
    std::cerr << "bench_render: " << e.what() << "\n";
    return 1;
  }
}
