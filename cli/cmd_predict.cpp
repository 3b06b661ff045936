// `infinisplat predict`: one photograph -> Gaussians in a standard 3DGS PLY.
#include <chrono>
#include <filesystem>
#include <iostream>
#include <sstream>

#include <torch/torch.h>

#include "cli/commands.h"
#include "cli/scene_camera.h"
#include "core/args.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/runtime.h"
#include "geometry/camera_torch.h"
#include "geometry/image_ops.h"
#include "io/atomic_file.h"
#include "io/checkpoint.h"
#include "io/csv.h"
#include "io/depth_io.h"
#include "io/exif.h"
#include "io/image_io.h"
#include "io/ply.h"
#include "io/tensor_image.h"
#include "model/model_io.h"
#include "render/prune.h"

namespace isplat::cli {
namespace fs = std::filesystem;

namespace {
// The working size: the training resolution's area at the photo's aspect, in multiples of 16.
std::pair<int, int> working_size(const Checkpoint& ck, int width, int height, int64_t override_w, int64_t override_h) {
  if (override_w > 0 && override_h > 0) {
    ISPLAT_CHECK(override_w <= max_image_pixels() / override_h, "predict: --width x --height = ", override_w, "x",
                 override_h, " is above runtime.max_image_pixels");
    return {static_cast<int>(override_w), static_cast<int>(override_h)};
  }
  int64_t tw = 256, th = 192;
  try {
    const auto cfg = parse_json(ck.config_json(), "stored config");
    tw = cfg.at("data").at("tuples").at("width").get<int64_t>();
    th = cfg.at("data").at("tuples").at("height").get<int64_t>();
  } catch (const std::exception&) {  // no training size stored (e.g. a converted checkpoint): the default
  }
  if (tw < 16 || th < 16 || tw > max_image_pixels() / th) tw = 256, th = 192;
  const double area = static_cast<double>(tw) * th, aspect = static_cast<double>(width) / height;
  auto r16 = [](double x) { return std::max(16, static_cast<int>(std::lround(x / 16.0)) * 16); };
  return {r16(std::sqrt(area * aspect)), r16(std::sqrt(area / aspect))};
}
}  // namespace

int run_predict(int argc, char** argv) {
  std::string checkpoint, image_path, depth_model, depth_path, prompts_path, out;
  double fx = 0, fy = 0, cx = -1, cy = -1, hfov = 0, prune_opacity = 0.02, prune_contribution = 0;
  MergeOptions merge;  // off unless --merge-cell
  int64_t threads = 0, width = 0, height = 0, seed = 0, prune_views = 4, fill_px = -1;
  bool keep_outside = false;
  std::vector<std::string> sets;
  ArgParser args("infinisplat predict",
                 "Turn one photograph into a 3D Gaussian scene (standard 3DGS PLY) with a trained "
                 "checkpoint. Intrinsics: --fx, else the photo's EXIF, else --hfov (default: "
                 "the model's prior.hfov_deg).");
  args.option("--checkpoint", checkpoint, "trained checkpoint (.safetensors)", "FILE");
  args.option("--image", image_path, "the photograph (PNG/JPG, any size)", "FILE");
  args.option("--out", out, "output PLY (a .camera.json is written beside it)", "FILE");
  args.option("--depth-model", depth_model, "TorchScript depth model instead of the checkpoint's prior", "FILE");
  args.option("--depth", depth_path, "metric depth (EXR, planar metres) instead of a prior", "FILE");
  args.option("--prompts", prompts_path, "sparse depth prompts, CSV with columns u,v,z (photo pixels, metres)", "FILE");
  args.option("--fx", fx, "focal length in photo pixels (fy = fx unless --fy)");
  args.option("--fy", fy, "vertical focal length in photo pixels");
  args.option("--cx", cx, "principal point x in photo pixels (default: centre)");
  args.option("--cy", cy, "principal point y in photo pixels (default: centre)");
  args.option("--hfov", hfov, "horizontal field of view in degrees when neither --fx nor EXIF is available");
  args.option("--fill-holes", fill_px,
              "fill invalid depth within this many pixels of valid depth before sampling, so small holes in --depth "
              "get Gaussians (0 = off; -1, the default: the checkpoint's sampler.fill_px)",
              "N");
  args.option("--width", width, "working width (default: the training resolution's area at the photo's aspect)");
  args.option("--height", height, "working height");
  args.option("--prune-opacity", prune_opacity, "drop Gaussians below this opacity (0 = keep all)");
  args.option("--prune-contribution", prune_contribution,
              "drop Gaussians whose largest rendered weight (alpha x transmittance) in the source view and "
              "--prune-views nearby views stays below this (0 = off; 0.01 is a good start)");
  args.option("--prune-views", prune_views, "virtual views for --prune-contribution: 0, 2, 4 or 6");
  args.option("--merge-cell", merge.cell_px,
              "merge the flat, single-coloured Gaussians of each cell of this many pixels into one (0 = off)");
  args.option("--merge-color", merge.max_color,
              "largest colour difference within a merged cell (in --merge-color-space)");
  args.option("--merge-color-space", merge.color_space,
              "where --merge-color is measured: linear (the stored colours) or srgb (the metrics' space)");
  args.option("--merge-flatness", merge.max_flatness, "largest thickness / width of a merged Gaussian (1 = any)");
  args.option("--merge-normal-cos", merge.min_normal_cos,
              "smallest cosine between a flat member's normal and the merged normal (0 = any)");
  args.flag("--merge-split", merge.split, "merge each single-coloured part of a cell that cannot merge whole");
  args.option("--merge-levels", merge.levels, "merge passes with cells of 1, 2, 4, ... times --merge-cell");
  args.option("--merge-level-color", merge.level_color, "each further merge level multiplies --merge-color by this");
  args.flag("--keep-outside", keep_outside, "keep Gaussians whose centre leaves the source view");
  args.repeated("--set", sets, "override a key of the checkpoint's model config, e.g. prior.sparse.noise=0.01",
                "KEY=VALUE");
  args.option("--seed", seed, "sampler seed");
  args.option("--threads", threads, "threads (0 = all cores)");
  if (!args.parse(argc, argv, 2)) return 0;
  ISPLAT_CHECK(!checkpoint.empty() && !image_path.empty() && !out.empty(),
               "predict: --checkpoint, --image and --out are required (see --help)");
  ISPLAT_CHECK((depth_model.empty() + depth_path.empty() + prompts_path.empty()) >= 2,
               "predict: give at most one of --depth-model, --depth, --prompts");
  {  // Neither output may be one of the inputs (the same path, a hard link, a symlinked folder).
    const std::vector<NamedPath> inputs = {{"--checkpoint", checkpoint},
                                           {"--image", image_path},
                                           {"--depth", depth_path},
                                           {"--prompts", prompts_path},
                                           {"--depth-model", depth_model}};
    refuse_output_over_input("predict", {"--out", out}, inputs);
    refuse_output_over_input("predict", {"--out's camera JSON", camera_sidecar_path(out)}, inputs);
  }
  // The merge flags pass the config schema's bounds, with its error naming the key.
  merge = config_from_json<MergeOptions>(config_to_json(merge), "predict's --merge-* flags");
  configure_threads(threads);
  remove_temporaries_on_signal();  // SIGINT/SIGTERM leave neither output nor a temporary behind
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();

  if (fill_px != -1) sets.push_back(cat("sampler.fill_px=", fill_px));  // the schema refuses other negatives
  if (!depth_model.empty()) sets.insert(sets.end(), {"prior.type=torchscript", "prior.torchscript=" + depth_model});
  if (!depth_path.empty()) sets.push_back("prior.type=dataset");
  if (!prompts_path.empty()) sets.push_back("prior.type=sparse");
  const Checkpoint ck = load_checkpoint(checkpoint);
  auto pipeline = load_pipeline(ck, checkpoint, sets);

  cv::Mat photo = read_image(image_path);
  const int W0 = photo.cols, H0 = photo.rows;
  Intrinsics intr;
  std::string k_source;
  if (fx > 0) {
    intr = {fx, fy > 0 ? fy : fx, cx >= 0 ? cx : W0 / 2.0, cy >= 0 ? cy : H0 / 2.0, W0, H0};
    k_source = "given";
  } else {
    const ExifFocal exif = read_exif_focal(read_file_bytes(image_path));
    if (exif.focal_35mm) {
      const double f = fx_from_35mm(*exif.focal_35mm, W0, H0);
      intr = {f, f, W0 / 2.0, H0 / 2.0, W0, H0};
      k_source = cat("EXIF (", *exif.focal_35mm, " mm, 35 mm equivalent)");
    } else {
      const double fov = hfov > 0 ? hfov : pipeline->model()->options.prior.hfov_deg;
      intr = Intrinsics::from_hfov(fov * M_PI / 180.0, W0, H0);
      k_source = cat("estimated from a ", fov, " degree field of view");
    }
  }
  const auto [Wm, Hm] = working_size(ck, W0, H0, width, height);
  cv::Mat image = resize_image(photo, Wm, Hm);
  const Intrinsics work = intr.resized(Wm, Hm);
  View view{work, Pose::Identity()};
  PriorInput in;
  in.image = image_to_tensor(image);
  in.K = to_camera(view).K;
  in.seed = static_cast<uint64_t>(seed);
  if (!depth_path.empty()) {
    const DepthMap d = read_depth_exr(depth_path);
    in.depth = map_to_tensor(resize_depth(d.depth, Wm, Hm));
    in.valid = (in.depth > 0).to(torch::kFloat32);
  }
  if (!prompts_path.empty()) {
    const CsvTable t = read_csv(prompts_path);
    auto p = torch::empty({static_cast<int64_t>(t.size()), 3});
    for (size_t r = 0; r < t.size(); ++r) {
      p[r][0] = t.number(r, "u") * Wm / W0;
      p[r][1] = t.number(r, "v") * Hm / H0;
      p[r][2] = t.number(r, "z");
    }
    in.prompts = p;
  }
  const Prediction pred = pipeline->run(in, torch::eye(4), false);
  Gaussians g = pred.gaussians;
  const int64_t made = g.count();
  int64_t outside = 0;
  if (!keep_outside) {
    auto uv = project_points(g.means, in.K);
    auto keep = (g.means.select(1, 2) > 0) & (uv.select(1, 0) >= 0) & (uv.select(1, 0) < Wm) & (uv.select(1, 1) >= 0) &
                (uv.select(1, 1) < Hm);
    outside = made - keep.sum().item<int64_t>();
    g = g.index(keep);
  }
  PruneOptions po;
  po.enabled = true;
  po.min_opacity = prune_opacity;
  po.min_contribution = prune_contribution;
  po.views = prune_views;
  po.merge = merge;
  const auto t_prune = Clock::now();
  const PruneResult pruned = prune_gaussians(g, to_camera(view), po);
  const double prune_ms = ms_since(t_prune);
  g = pruned.kept;
  const int64_t faint = pruned.low_opacity;
  ISPLAT_CHECK(g.count() > 0, "predict: no Gaussian is left of ", made, " (", outside, " outside the view, ", faint,
               " below opacity ", prune_opacity, ", ", pruned.low_contribution, " below contribution, ",
               pruned.merge.removed(), " merged); not writing an empty scene to ", out);
  PlyOptions ply;  // what pruning removed travels with the scene
  std::ostringstream pruning;
  pruning << "pruning: decoded " << made << ", outside_view " << outside << ", low_opacity " << faint
          << " (min_opacity " << prune_opacity << "), low_contribution " << pruned.low_contribution
          << " (min_contribution " << prune_contribution << ", views " << (prune_contribution > 0 ? prune_views : 0)
          << "), merged_away " << pruned.merge.removed() << ", kept " << g.count();
  ply.comments.push_back(pruning.str());
  {  // Both files new or neither: each is written whole to its temporary, then both are renamed together.
    AtomicPath ply_file(out), camera_file(camera_sidecar_path(out));
    write_ply(ply_file.temp(), g, pipeline->model()->options.composer.linear_rgb, ply);
    write_scene_camera(camera_file.temp(), view, pred.supports.depth.median().item<double>());
    commit_together({&camera_file, &ply_file});
  }

  std::cout << "photo        " << image_path << " (" << W0 << "x" << H0 << "), working size " << Wm << "x" << Hm
            << "\n";
  std::cout << "intrinsics   fx " << std::fixed << std::setprecision(1) << intr.fx << " px, " << k_source << "\n";
  std::cout << "depth prior  " << pipeline->prior().describe() << "\n";
  std::cout << "supports     " << pred.supports.count() << "\n";
  std::cout << "Gaussians    " << g.count() << " written of " << made << " decoded (pruned: " << outside
            << " outside the view, " << faint << " below opacity " << std::setprecision(3) << std::defaultfloat
            << prune_opacity << ", " << pruned.low_contribution << " below contribution " << prune_contribution
            << " over the source and " << (prune_contribution > 0 ? prune_views : 0) << " nearby views, "
            << pruned.merge.removed() << " merged into neighbours)\n";
  if (merge.cell_px > 0)
    std::cout << "merging      groups refused: " << pruned.merge.refused_color << " by colour, "
              << pruned.merge.refused_shape << " by flatness, " << pruned.merge.refused_normal << " by normals; "
              << pruned.merge.alone << " Gaussians alone in their cell\n";
  std::cout << "time (ms)   ";
  double stages = prune_ms;
  for (const char* k : {"prior", "sampler", "encoder", "decoder", "composer"})
    if (pred.timings_ms.count(k)) {
      std::cout << " " << k << " " << std::fixed << std::setprecision(0) << pred.timings_ms.at(k);
      stages += pred.timings_ms.at(k);
    }
  std::cout << " prune " << std::fixed << std::setprecision(0) << prune_ms;
  // The stages are the prediction itself; the total adds loading the checkpoint and photo and writing the files.
  std::cout << " | stages " << stages << " | total with loading and writing " << ms_since(t_start) << "\n";
  std::cout << "wrote        " << fs::absolute(out).string() << "\n             "
            << fs::absolute(camera_sidecar_path(out)).string() << "\n";
  return 0;
}

}  // namespace isplat::cli
