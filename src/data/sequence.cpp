// Frame loading for every supported layout, Hypersim's tone map, frustum overlap and baselines.
#include "data/sequence.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <optional>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/error.h"
#include "geometry/image_ops.h"
#include "io/atomic_file.h"
#include "io/hdf5_io.h"
#include "io/image_io.h"

namespace isplat {
namespace {

cv::Mat hdf5_to_mat(const H5Array<float>& a, int channels, const std::string& path) {
  const bool ok = (channels == 1 && a.shape.size() == 2) || (channels == 3 && a.shape.size() == 3 && a.shape[2] == 3);
  if (!ok) {
    std::string s;
    for (auto d : a.shape) s += (s.empty() ? "" : "x") + std::to_string(d);
    fail(path, ": expected a ", channels == 1 ? "[H, W]" : "[H, W, 3]", " dataset, got shape [", s, "]");
  }
  cv::Mat m(static_cast<int>(a.shape[0]), static_cast<int>(a.shape[1]), channels == 1 ? CV_32FC1 : CV_32FC3);
  std::memcpy(m.data, a.values.data(), a.values.size() * sizeof(float));
  return m;
}

void check_size(const cv::Mat& m, const View& view, const std::string& path) {
  if (m.cols != view.intr.width || m.rows != view.intr.height)
    fail(path, ": image is ", m.cols, "x", m.rows, " but its camera says ", view.intr.width, "x", view.intr.height);
}

// `geometry` (optional) marks pixels with geometry; Hypersim's tone map counts only those
// (its render_entity_id != -1), which is where depth is finite.
cv::Mat load_color(const FrameRecord& f, const cv::Mat& geometry) {
  if (f.color == ColorSource::Image) return read_image(f.image_path);
  cv::Mat hdr = hdf5_to_mat(read_hdf5_float(f.image_path), 3, f.image_path);
  return hypersim_tonemap(hdr, geometry.size() == hdr.size() ? geometry : cv::Mat());
}

cv::Mat load_raw_depth(const Sequence& seq, const FrameRecord& f) {
  switch (f.depth) {
    case DepthSource::None:
      return cv::Mat();
    case DepthSource::HypersimRayHdf5: {
      ISPLAT_CHECK(seq.hypersim, f.depth_path, ": Hypersim depth needs the scene's camera model");
      cv::Mat dist = hdf5_to_mat(read_hdf5_float(f.depth_path), 1, f.depth_path);
      for (int i = 0; i < dist.rows; ++i) {
        float* d = dist.ptr<float>(i);
        for (int j = 0; j < dist.cols; ++j)
          d[j] = static_cast<float>(d[j] * hypersim_planar_factor(*seq.hypersim, j + 0.5, i + 0.5));
      }
      return dist;
    }
    case DepthSource::PlanarExr:
      return read_exr_channel(f.depth_path);
    case DepthSource::Png16Millimetres: {
      cv::Mat mm = read_png16(f.depth_path), m;
      mm.convertTo(m, CV_32F, 1e-3);
      return m;
    }
    case DepthSource::RawFloat32: {
      const std::string bytes = read_file_bytes(f.depth_path);
      const size_t want = static_cast<size_t>(f.view.intr.width) * f.view.intr.height * sizeof(float);
      if (bytes.size() != want)
        fail(f.depth_path, ": raw float32 depth has ", bytes.size(), " bytes, expected ", want, " for ",
             f.view.intr.width, "x", f.view.intr.height);
      cv::Mat m(f.view.intr.height, f.view.intr.width, CV_32FC1);
      std::memcpy(m.data, bytes.data(), want);
      return m;
    }
  }
  return cv::Mat();
}

// Removes lens distortion with K kept as the new camera. The maps are built once per frame and serve
// both the colour (bilinear) and the depth (nearest), which share the intrinsics' size.
struct Undistorter {
  cv::Mat map1, map2;
  Undistorter(const Intrinsics& intr, const std::vector<double>& dist) {
    cv::Mat K(3, 3, CV_64F), D(1, static_cast<int>(dist.size()), CV_64F);
    const Eigen::Matrix3d Ke = intr.K();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) K.at<double>(i, j) = Ke(i, j);
    for (size_t i = 0; i < dist.size(); ++i) D.at<double>(0, static_cast<int>(i)) = dist[i];
    cv::initUndistortRectifyMap(K, D, cv::Mat(), K, cv::Size(intr.width, intr.height), CV_32FC1, map1, map2);
  }
  void apply(cv::Mat& m, bool nearest) const {
    cv::Mat out;
    cv::remap(m, out, map1, map2, nearest ? cv::INTER_NEAREST : cv::INTER_LINEAR, cv::BORDER_CONSTANT,
              cv::Scalar::all(nearest ? std::numeric_limits<double>::quiet_NaN() : 0.0));
    m = out;
  }
};

}  // namespace

LoadedFrame load_frame(const Sequence& sequence, size_t index, bool with_depth) {
  ISPLAT_CHECK(index < sequence.frames.size(), sequence.id(), ": frame index ", index, " out of range (",
               sequence.frames.size(), " frames)");
  const FrameRecord& f = sequence.frames[index];
  LoadedFrame out;
  out.view = f.view;
  cv::Mat raw_depth, geometry;
  if (f.depth != DepthSource::None && (with_depth || f.color == ColorSource::HypersimHdf5)) {
    raw_depth = load_raw_depth(sequence, f);
    geometry = raw_depth == raw_depth;  // finite -> 255
  }
  out.image = load_color(f, geometry);
  if (f.rescale_to_image && (out.image.cols != f.view.intr.width || out.image.rows != f.view.intr.height)) {
    const double ax = static_cast<double>(out.image.cols) / f.view.intr.width;
    const double ay = static_cast<double>(out.image.rows) / f.view.intr.height;
    if (std::fabs(ax / ay - 1.0) > 0.01)
      fail(f.image_path, ": image is ", out.image.cols, "x", out.image.rows, ", not a resized copy of the ",
           f.view.intr.width, "x", f.view.intr.height, " camera (aspect differs)");
    out.view.intr = f.view.intr.resized(out.image.cols, out.image.rows);
  }
  check_size(out.image, out.view, f.image_path);
  std::optional<Undistorter> undistorter;
  if (!f.distortion.empty()) {
    undistorter.emplace(out.view.intr, f.distortion);
    undistorter->apply(out.image, false);
  }
  if (with_depth && f.depth != DepthSource::None) {
    cv::Mat raw = raw_depth;
    if (f.rescale_to_image && (raw.cols != out.view.intr.width || raw.rows != out.view.intr.height) &&
        std::fabs(static_cast<double>(raw.cols) * out.view.intr.height / (raw.rows * out.view.intr.width) - 1.0) < 0.01)
      raw = resize_depth(raw, out.view.intr.width, out.view.intr.height);
    check_size(raw, out.view, f.depth_path);
    if (undistorter) undistorter->apply(raw, true);
    out.depth = sanitize_depth(raw);
  }
  return out;
}

double hypersim_exposure(const cv::Mat& linear_rgb, const cv::Mat& valid) {
  ISPLAT_CHECK(linear_rgb.type() == CV_32FC3, "hypersim_exposure expects CV_32FC3");
  constexpr double kGamma = 1.0 / 2.2, kPercentile = 0.90, kTarget = 0.8, kEps = 1e-4;
  std::vector<float> brightness;
  brightness.reserve(linear_rgb.total());
  for (int i = 0; i < linear_rgb.rows; ++i) {
    const cv::Vec3f* p = linear_rgb.ptr<cv::Vec3f>(i);
    const uint8_t* v = valid.empty() ? nullptr : valid.ptr<uint8_t>(i);
    for (int j = 0; j < linear_rgb.cols; ++j) {
      if (v && !v[j]) continue;
      const float b = 0.3f * p[j][0] + 0.59f * p[j][1] + 0.11f * p[j][2];
      if (std::isfinite(b)) brightness.push_back(b);
    }
  }
  if (brightness.empty()) return 0.0;
  // numpy.percentile's default linear interpolation between order statistics.
  const double pos = kPercentile * (brightness.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos)), hi = std::min(lo + 1, brightness.size() - 1);
  std::nth_element(brightness.begin(), brightness.begin() + lo, brightness.end());
  const double a = brightness[lo];
  const double b = hi == lo ? a : *std::min_element(brightness.begin() + lo + 1, brightness.end());
  const double current = a + (pos - lo) * (b - a);
  return current < kEps ? 0.0 : std::pow(kTarget, 1.0 / kGamma) / current;
}

cv::Mat apply_exposure_gamma(const cv::Mat& linear_rgb, double scale) {
  ISPLAT_CHECK(linear_rgb.type() == CV_32FC3, "apply_exposure_gamma expects CV_32FC3");
  constexpr double kGamma = 1.0 / 2.2;
  cv::Mat out(linear_rgb.size(), CV_32FC3);
  for (int i = 0; i < linear_rgb.rows; ++i) {
    const cv::Vec3f* p = linear_rgb.ptr<cv::Vec3f>(i);
    cv::Vec3f* o = out.ptr<cv::Vec3f>(i);
    for (int j = 0; j < linear_rgb.cols; ++j)
      for (int c = 0; c < 3; ++c) {
        const double x = std::isfinite(p[j][c]) ? std::max(0.0, scale * p[j][c]) : 0.0;
        o[j][c] = static_cast<float>(std::min(1.0, std::pow(x, kGamma)));
      }
  }
  return out;
}

cv::Mat hypersim_tonemap(const cv::Mat& linear_rgb, const cv::Mat& valid) {
  return apply_exposure_gamma(linear_rgb, hypersim_exposure(linear_rgb, valid));
}

double frustum_overlap(const View& source, const DepthMap& source_depth, const View& target, int grid) {
  if (source_depth.depth.empty()) return 0.0;
  const int H = source_depth.depth.rows, W = source_depth.depth.cols;
  const double sx = static_cast<double>(source.intr.width) / W, sy = static_cast<double>(source.intr.height) / H;
  const int gx = std::max(1, std::min(grid, W)), gy = std::max(1, std::min(grid * H / std::max(1, W), H));
  const Pose to_target = target.T_cw * invert_pose(source.T_cw);
  int valid = 0, inside = 0;
  for (int a = 0; a < gy; ++a)
    for (int b = 0; b < gx; ++b) {
      const int i = static_cast<int>((a + 0.5) * H / gy), j = static_cast<int>((b + 0.5) * W / gx);
      if (!source_depth.valid.at<uint8_t>(i, j)) continue;
      ++valid;
      const double z = source_depth.depth.at<float>(i, j);
      const Eigen::Vector3d Xs = source.intr.backproject((j + 0.5) * sx, (i + 0.5) * sy, z);
      const Eigen::Vector3d Xt = transform_point(to_target, Xs);
      if (Xt.z() <= 1e-6) continue;
      const Eigen::Vector2d uv = target.intr.project(Xt);
      if (uv.x() >= 0 && uv.x() < target.intr.width && uv.y() >= 0 && uv.y() < target.intr.height) ++inside;
    }
  return valid ? static_cast<double>(inside) / valid : 0.0;
}

double baseline(const View& a, const View& b) {
  return (camera_center(a.T_cw) - camera_center(b.T_cw)).norm();
}

}  // namespace isplat
