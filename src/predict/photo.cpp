// One photo -> Gaussians: the working size, intrinsics, prior input, pipeline, dropping and pruning.
#include "predict/photo.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <torch/torch.h>

#include "core/config.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/runtime.h"
#include "geometry/camera_torch.h"
#include "geometry/image_ops.h"
#include "io/atomic_file.h"
#include "io/checkpoint.h"
#include "io/exif.h"
#include "io/tensor_image.h"
#include "model/model_io.h"

namespace isplat {

namespace {

struct PhotoIntrinsics {
  Intrinsics intrinsics;
  std::string source;
};

// fx (with fy, cx, cy), else the EXIF 35 mm focal length of `exif_from`, else hfov, else `default_hfov_deg`.
PhotoIntrinsics photo_intrinsics(const PhotoIntrinsicsOptions& o, int width, int height, const std::string& exif_from,
                                 double default_hfov_deg) {
  if (o.fx) {
    const Intrinsics k{*o.fx, o.fy ? *o.fy : *o.fx, o.cx ? *o.cx : width / 2.0, o.cy ? *o.cy : height / 2.0, width,
                       height};
    return {k, "given"};
  }
  const ExifFocal exif = exif_from.empty() ? ExifFocal{} : read_exif_focal(read_file_bytes(exif_from));
  if (exif.focal_35mm) {
    const double f = fx_from_35mm(*exif.focal_35mm, width, height);
    return {Intrinsics{f, f, width / 2.0, height / 2.0, width, height},
            cat("EXIF (", *exif.focal_35mm, " mm, 35 mm equivalent)")};
  }
  const double fov = o.hfov ? *o.hfov : default_hfov_deg;
  return {Intrinsics::from_hfov(fov * M_PI / 180.0, width, height),
          cat("estimated from a ", fov, " degree field of view")};
}

}  // namespace

std::string option_name(OptionNames names, const std::string& key) {
  if (names == OptionNames::Keywords) return key;
  std::string flag = "--" + key;
  std::replace(flag.begin(), flag.end(), '_', '-');
  return flag;
}

void check_photo_options(const PhotoPredictOptions& o) {
  const auto name = [&](const char* key) { return option_name(o.names, key); };
  const PhotoIntrinsicsOptions& k = o.intrinsics;
  ISPLAT_CHECK(k.fx || (!k.fy && !k.cx && !k.cy), "predict: ", name("fy"), ", ", name("cx"), " and ", name("cy"),
               " refine ", name("fx"), "; give ", name("fx"), " too (without ", name("fx"),
               " the intrinsics come from EXIF or ", name("hfov"), ", which they would not change)");
  for (const auto& [key, value] : {std::pair{"fx", k.fx}, std::pair{"fy", k.fy}})
    ISPLAT_CHECK(!value || (*value > 0 && std::isfinite(*value)), "predict: ", name(key),
                 " must be a positive focal length in pixels, got ", *value);
  for (const auto& [key, value] : {std::pair{"cx", k.cx}, std::pair{"cy", k.cy}})
    ISPLAT_CHECK(!value || (*value >= 0 && std::isfinite(*value)), "predict: ", name(key),
                 " must be a pixel coordinate in the photo, got ", *value);
  ISPLAT_CHECK(!k.hfov || (*k.hfov >= 1 && *k.hfov <= 179), "predict: ", name("hfov"),
               " must be in [1, 179] degrees, got ", *k.hfov);
  ISPLAT_CHECK((o.width > 0) == (o.height > 0), "predict: give ", name("width"), " and ", name("height"),
               " together (got ", o.width, "x", o.height, ")");
  ISPLAT_CHECK(o.width % 16 == 0 && o.height % 16 == 0, "predict: ", name("width"), " ", o.width, " and ",
               name("height"), " ", o.height, " must be multiples of 16 (the encoder's patch)");
  ISPLAT_CHECK(o.width >= 0 && o.height >= 0, "predict: ", name("width"), " and ", name("height"),
               " must be positive (0 for the default), got ", o.width, "x", o.height);
  ISPLAT_CHECK(o.view_floor >= 0 && o.view_floor <= 4, "predict: ", name("view_floor"),
               " must be in [0, 4] pixels, got ", o.view_floor);
  ISPLAT_CHECK(o.prune_opacity >= 0 && o.prune_opacity <= 1, "predict: ", name("prune_opacity"),
               " must be in [0, 1], got ", o.prune_opacity);
  ISPLAT_CHECK(o.prune_contribution >= 0 && o.prune_contribution <= 1, "predict: ", name("prune_contribution"),
               " must be in [0, 1], got ", o.prune_contribution);
  ISPLAT_CHECK(o.prune_views == 0 || o.prune_views == 2 || o.prune_views == 4 || o.prune_views == 6,
               "predict: ", name("prune_views"), " must be 0, 2, 4 or 6, got ", o.prune_views);
}

PhotoPredictor::PhotoPredictor(const std::string& checkpoint, const std::vector<std::string>& overrides) {
  const Checkpoint ck = load_checkpoint(checkpoint);
  pipeline_ = load_pipeline(ck, checkpoint, overrides);
  trained_floor_px_ = pipeline_->model()->options.composer.scale_floor_px;
  try {
    const auto cfg = parse_json(ck.config_json(), "stored config");
    train_width_ = cfg.at("data").at("tuples").at("width").get<int64_t>();
    train_height_ = cfg.at("data").at("tuples").at("height").get<int64_t>();
  } catch (const std::exception&) {  // no training size stored (e.g. a converted checkpoint): the default
  }
}

PhotoPredictor::~PhotoPredictor() = default;

std::pair<int, int> PhotoPredictor::working_size(int width, int height, const PhotoPredictOptions& o) const {
  const auto name = [&](const char* key) { return option_name(o.names, key); };
  auto r16 = [](double x) { return std::max(16, static_cast<int>(std::lround(x / 16.0)) * 16); };
  if (o.photo_size) {
    const int w = r16(width), h = r16(height);
    ISPLAT_CHECK(w <= max_image_pixels() / h, "predict: ", name("photo_size"), " ", w, "x", h,
                 " is above runtime.max_image_pixels = ", max_image_pixels(), " (give ", name("width"), " and ",
                 name("height"), ")");
    return {w, h};
  }
  if (o.width > 0 && o.height > 0) {
    ISPLAT_CHECK(o.width <= max_image_pixels() / o.height, "predict: ", name("width"), " x ", name("height"), " = ",
                 o.width, "x", o.height, " is above runtime.max_image_pixels");
    return {static_cast<int>(o.width), static_cast<int>(o.height)};
  }
  int64_t tw = train_width_, th = train_height_;
  if (tw < 16 || th < 16 || tw > max_image_pixels() / th) tw = 256, th = 192;
  const double area = static_cast<double>(tw) * th, aspect = static_cast<double>(width) / height;
  return {r16(std::sqrt(area * aspect)), r16(std::sqrt(area / aspect))};
}

PhotoPrediction PhotoPredictor::predict(const PhotoInput& input, const PhotoPredictOptions& o,
                                        const PhotoHooks& hooks) {
  check_photo_options(o);
  const auto name = [&](const char* key) { return option_name(o.names, key); };
  const cv::Mat& photo = input.photo;
  ISPLAT_CHECK(!photo.empty() && photo.type() == CV_32FC3, "predict: the photo ", input.label,
               " must be float RGB (CV_32FC3), not empty");
  const int W0 = photo.cols, H0 = photo.rows;
  const PhotoIntrinsicsOptions& k = o.intrinsics;
  ISPLAT_CHECK(!k.cx || *k.cx <= W0, "predict: ", name("cx"), " ", *k.cx, " lies outside the photo ", input.label, " (",
               W0, "x", H0, "): the principal point's x is in [0, ", W0, "]");
  ISPLAT_CHECK(!k.cy || *k.cy <= H0, "predict: ", name("cy"), " ", *k.cy, " lies outside the photo ", input.label, " (",
               W0, "x", H0, "): the principal point's y is in [0, ", H0, "]");

  PhotoPrediction r;
  PhotoFrame& frame = r.frame;
  PhotoIntrinsics intrinsics = photo_intrinsics(k, W0, H0, input.exif_from, pipeline_->model()->options.prior.hfov_deg);
  frame.intrinsics = intrinsics.intrinsics;
  frame.intrinsics_source = std::move(intrinsics.source);
  const auto [Wm, Hm] = working_size(W0, H0, o);
  frame.width = Wm, frame.height = Hm;
  frame.view = View{frame.intrinsics.resized(Wm, Hm), Pose::Identity()};
  PriorInput& in = frame.input;
  in.image = image_to_tensor(resize_image(photo, Wm, Hm));
  in.K = to_camera(frame.view).K;
  in.seed = o.seed;
  if (!input.depth.empty()) {  // a resized copy of the photo's view is fine, another aspect is another framing
    const cv::Mat& d = input.depth;
    const double ratio = (static_cast<double>(d.cols) / d.rows) / (static_cast<double>(W0) / H0);
    ISPLAT_CHECK(std::fabs(ratio - 1.0) <= 0.01, "predict: ", name("depth"),
                 input.depth_label.empty() ? "" : " " + input.depth_label, " is ", d.cols, "x", d.rows,
                 ", not a resized copy of the photo ", input.label, " (", W0, "x", H0, "): the aspects differ");
    in.depth = map_to_tensor(resize_depth(d, Wm, Hm));
    in.valid = (in.depth > 0).to(torch::kFloat32);
  }
  if (!input.prompts.empty()) {  // photo pixels -> working-size pixels
    auto p = torch::empty({static_cast<int64_t>(input.prompts.size()), 3});
    for (size_t i = 0; i < input.prompts.size(); ++i) {
      const auto& [u, v, z] = input.prompts[i];
      p[i][0] = u * Wm / W0;
      p[i][1] = v * Hm / H0;
      p[i][2] = z;
    }
    in.prompts = p;
  }

  // The floor the Gaussians are made with: the checkpoint's, raised to the view floor for viewers.
  double& floor_px = pipeline_->model()->options.composer.scale_floor_px;
  floor_px = std::max(trained_floor_px_, o.view_floor);
  r.scale_floor_px = floor_px;
  std::function<void(PriorOutput&)> after_prior;
  if (hooks.after_prior) after_prior = [&](PriorOutput& prior) { hooks.after_prior(prior, frame); };
  r.prediction = pipeline_->run(in, torch::eye(4), false, after_prior);

  Gaussians g = r.prediction.gaussians;
  if (hooks.after_decode) hooks.after_decode(g, frame);
  r.decoded = g.count();
  if (!o.keep_outside) {  // centres that leave the source view
    auto uv = project_points(g.means, in.K);
    auto keep = (g.means.select(1, 2) > 0) & (uv.select(1, 0) >= 0) & (uv.select(1, 0) < Wm) & (uv.select(1, 1) >= 0) &
                (uv.select(1, 1) < Hm);
    r.outside = r.decoded - keep.sum().item<int64_t>();
    g = g.index(keep);
  }
  PruneOptions po;
  po.enabled = true;
  po.min_opacity = o.prune_opacity;
  po.min_contribution = o.prune_contribution;
  po.views = o.prune_views;
  po.merge = o.merge;
  const auto t_prune = std::chrono::steady_clock::now();
  r.pruned = prune_gaussians(g, to_camera(frame.view), po);
  r.prune_ms = ms_since(t_prune);
  r.gaussians = r.pruned.kept;
  return r;
}

}  // namespace isplat
