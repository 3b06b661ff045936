// `infinisplat predict`: one photograph -> Gaussians in a standard 3DGS PLY.
#include <cctype>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <torch/torch.h>

#include "cli/commands.h"
#include "cli/scene_camera.h"
#include "core/args.h"
#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/paths.h"
#include "core/precision.h"
#include "core/progress.h"
#include "core/runtime.h"
#include "geometry/camera_torch.h"
#include "io/atomic_file.h"
#include "io/csv.h"
#include "io/depth_io.h"
#include "io/image_io.h"
#include "io/ply.h"
#include "metrics/display.h"
#include "model/model_io.h"
#include "predict/photo.h"
#include "render/prune.h"
#include "render/scale_align.h"
#include "sampler/sampler.h"

namespace isplat::cli {
namespace fs = std::filesystem;

namespace {
// The CLI's bounds on intrinsics and sizes: a focal length of 1e-3 or 1e9 pixels is a typo, not a lens.
constexpr double kMinFocal = 1e-2, kMaxFocal = 1e7, kMaxSide = 65536;

enum class InputKind { Image, Folder, List, Video };

std::string lower_extension(const fs::path& p) {
  std::string e = p.extension().string();
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

bool is_image_file(const fs::path& p) {
  static const std::set<std::string> kinds = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".webp", ".exr"};
  return kinds.count(lower_extension(p)) > 0;
}

InputKind input_kind(const std::string& path) {
  if (fs::is_directory(path)) return InputKind::Folder;
  const std::string e = lower_extension(path);
  if (e == ".txt" || e == ".lst" || e == ".list") return InputKind::List;
  if (e == ".mp4" || e == ".mov" || e == ".avi" || e == ".mkv" || e == ".webm" || e == ".m4v") return InputKind::Video;
  return InputKind::Image;
}

struct BatchInput {
  std::string path, name;  // name: the outputs' stem
  int64_t frame = -1;      // video frame index
};

// The images of a folder (sorted by name) or of a list file, each named by its stem; a stem that repeats gets
// _2, _3, ... in input order (stable, so a rerun finds the same outputs).
std::vector<BatchInput> image_inputs(const std::string& source, InputKind kind) {
  std::vector<BatchInput> inputs;
  if (kind == InputKind::Folder) {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(source))
      if (e.is_regular_file() && is_image_file(e.path())) files.push_back(e.path());
    std::sort(files.begin(), files.end());
    for (const auto& f : files) inputs.push_back({f.string(), f.stem().string()});
  } else {
    std::istringstream lines(read_file_bytes(source));
    std::string line;
    for (int64_t number = 1; std::getline(lines, line); ++number) {
      const size_t a = line.find_first_not_of(" \t\r"), b = line.find_last_not_of(" \t\r");
      if (a == std::string::npos || line[a] == '#') continue;
      fs::path p = line.substr(a, b - a + 1);
      if (p.is_relative()) p = fs::path(source).parent_path() / p;
      if (!fs::is_regular_file(p)) fail(source, ": line ", number, ": ", p.string(), ": no such file");
      inputs.push_back({p.string(), p.stem().string()});
    }
  }
  std::map<std::string, int64_t> seen;
  for (auto& in : inputs) {
    in.name = safe_name(in.name);
    if (const int64_t n = ++seen[in.name]; n > 1) in.name += cat("_", n);
  }
  return inputs;
}

// Every `every`-th frame of a video, by the count its container declares (frames past the real end fail by name).
std::vector<BatchInput> video_inputs(const std::string& source, int64_t every) {
  if (!fs::is_regular_file(source)) fail(source, ": no such file");
  cv::VideoCapture video(source);
  if (!video.isOpened()) fail(source, ": OpenCV cannot read this video");
  int64_t frames = static_cast<int64_t>(video.get(cv::CAP_PROP_FRAME_COUNT));
  if (frames <= 0) {  // no count in the container: count by decoding
    frames = 0;
    while (video.grab()) ++frames;
  }
  std::vector<BatchInput> inputs;
  char name[32];
  for (int64_t f = 0; f < frames; f += every) {
    std::snprintf(name, sizeof name, "frame_%06lld", static_cast<long long>(f));
    inputs.push_back({source, name, f});
  }
  return inputs;
}

// True when a PLY and its camera JSON are both there and read: what an earlier run finished (the two appear
// together, commit_together).
bool outputs_complete(const std::string& ply) {
  const std::string camera = camera_sidecar_path(ply);
  if (!fs::is_regular_file(ply) || !fs::is_regular_file(camera)) return false;
  try {
    double typical_depth = 0;
    read_scene_camera(camera, typical_depth);
    return read_ply(ply).count() > 0;
  } catch (const Error&) {
    return false;
  }
}
}  // namespace

int run_predict(int argc, char** argv) {
  std::string checkpoint, image_path, depth_model, depth_path, prompts_path, align_path, out;
  double fx = 0, fy = 0, cx = -1, cy = -1, hfov = 0;  // 0 and -1: not given
  PhotoPredictOptions photo_options;                  // the one-photo steps' options, at their defaults
  MergeOptions& merge = photo_options.merge;          // off unless --merge-cell
  int64_t threads = 0, seed = 0, fill_px = -1;
  std::string precision = "fp32";
  std::vector<std::string> sets;
  int64_t max_gaussians = 0, every = 1;
  ArgParser args("infinisplat predict",
                 "Turn a photograph into a 3D Gaussian scene (standard 3DGS PLY) with a trained "
                 "checkpoint; or every photo of a folder, of a list file or every frame of a video, in one "
                 "process with the model loaded once. Intrinsics: --fx, else the photo's EXIF, else --hfov "
                 "(default: the model's prior.hfov_deg).");
  args.option("--checkpoint", checkpoint, "trained checkpoint (.safetensors)", "FILE");
  args.option("--image", image_path,
              "the photograph (PNG/JPG, any size); or a folder of photos, a list file (.txt: one image path per line, "
              "relative to the list's folder; # comments) or a video (.mp4 .mov .avi .mkv .webm .m4v, frames through "
              "OpenCV)",
              "PATH");
  args.option("--out", out,
              "output PLY (a .camera.json is written beside it); for a folder, list or video: the output folder, one "
              "<name>.ply and <name>.camera.json per input (video: frame_<index>); inputs whose two files are already "
              "there and readable are skipped, so an interrupted run resumes",
              "PATH");
  args.option("--max-gaussians", max_gaussians,
              "at most this many Gaussians in each output (0 = no limit): when the checkpoint's sampler would place "
              "more supports, it places exactly this many instead (sampler.budget_mode = fixed; pixel mode becomes "
              "area), before decoding; the decoded set is never cut",
              "N");
  args.option("--every", every, "video: predict every N-th frame", "N").range(1, 1e9);
  args.option("--depth-model", depth_model, "TorchScript depth model instead of the checkpoint's prior", "FILE");
  args.option("--depth", depth_path, "metric depth (EXR, planar metres) instead of a prior", "FILE");
  args.option("--prompts", prompts_path, "sparse depth prompts, CSV with columns u,v,z (photo pixels, metres)", "FILE");
  args.option("--align-points", align_path,
              "scale the prediction to a capture's units (e.g. a COLMAP reconstruction): CSV with columns u,v,z "
              "(photo pixels, the capture's planar depth there); the scene is scaled about the camera by the median "
              "of z / predicted depth at those pixels",
              "FILE");
  args.option("--fx", fx, "focal length in photo pixels (fy = fx unless --fy)").range(kMinFocal, kMaxFocal, "pixels");
  args.option("--fy", fy, "vertical focal length in photo pixels (with --fx)").range(kMinFocal, kMaxFocal, "pixels");
  args.option("--cx", cx, "principal point x in photo pixels (default: centre; with --fx; inside the photo)")
      .range(0, kMaxSide, "pixels");
  args.option("--cy", cy, "principal point y in photo pixels (default: centre; with --fx; inside the photo)")
      .range(0, kMaxSide, "pixels");
  args.option("--hfov", hfov, "horizontal field of view in degrees when neither --fx nor EXIF is available")
      .range(1, 179, "degrees");
  args.option("--fill-holes", fill_px,
              "fill invalid depth within this many pixels of valid depth before sampling, so small holes in --depth "
              "get Gaussians (0 = off; -1, the default: the checkpoint's sampler.fill_px)",
              "N");  // the config schema's bounds on sampler.fill_px check it, naming the key
  args.option("--width", photo_options.width,
              "working width, a multiple of 16, with --height (default: the training resolution's area at the "
              "photo's aspect, in multiples of 16: the size the model was trained at, fastest and best scored; a "
              "viewer far above it sees gaps, which predict reports at 4x)")
      .range(16, kMaxSide, "pixels");
  args.option("--height", photo_options.height, "working height, a multiple of 16, with --width")
      .range(16, kMaxSide, "pixels");
  args.flag("--photo-size", photo_options.photo_size,
            "predict at the photo's own resolution (in multiples of 16) instead of the working size: more Gaussians, "
            "fewer gaps in large views, slower");
  args.option("--view-floor", photo_options.view_floor,
              cat("no written Gaussian narrower than this many working-size pixels at its depth (the composer's scale "
                  "floor, raised for viewers, who render above the working size: at ",
                  kViewFloorPx,
                  ", the default, a viewer at 4x sees almost no gaps, at a small cost at the working size); 0 = the "
                  "checkpoint's own composer.scale_floor_px"))
      .range(0, 4, "pixels");
  args.option("--prune-opacity", photo_options.prune_opacity, "drop Gaussians below this opacity (0 = keep all)")
      .range(0, 1);
  args.option("--prune-contribution", photo_options.prune_contribution,
              "drop Gaussians whose largest rendered weight (alpha x transmittance) in the source view and "
              "--prune-views nearby views stays below this (0 = off; 0.01 is a good start)")
      .range(0, 1);
  args.option("--prune-views", photo_options.prune_views, "virtual views for --prune-contribution: 0, 2, 4 or 6")
      .range(0, 6);
  args.option("--merge-cell", merge.cell_px,
              "merge the flat, single-coloured Gaussians of each cell of this many pixels into one (0 = off)");
  args.option("--merge-color", merge.max_color, "largest colour difference within a merged cell (stored colours)");
  args.option("--merge-flatness", merge.max_flatness, "largest thickness / width of a merged Gaussian (1 = any)");
  args.option("--merge-normal-cos", merge.min_normal_cos,
              "smallest cosine between a flat member's normal and the merged normal (0 = any)");
  args.flag("--merge-split", merge.split, "merge each single-coloured part of a cell that cannot merge whole");
  args.flag("--keep-outside", photo_options.keep_outside, "keep Gaussians whose centre leaves the source view");
  args.repeated("--set", sets, "override a key of the checkpoint's model config, e.g. prior.sparse.noise=0.01",
                "KEY=VALUE");
  args.option("--seed", seed, "sampler seed").range(0, 9.2e18);
  args.option("--threads", threads, "threads (0 = all cores)").range(0, kMaxThreads);
  args.option("--precision", precision,
              "the encoder's and decoder's matmuls: fp32, bf16 (fp32 accumulation) or auto (bf16 where the CPU has "
              "AVX512-BF16 or AMX)",
              "fp32|bf16|auto");
  if (!args.parse(argc, argv, 2)) return 0;
  ISPLAT_CHECK(!checkpoint.empty() && !image_path.empty() && !out.empty(),
               "predict: --checkpoint, --image and --out are required (see --help)");
  ISPLAT_CHECK((depth_model.empty() + depth_path.empty() + prompts_path.empty()) >= 2,
               "predict: give at most one of --depth-model, --depth, --prompts");
  ISPLAT_CHECK(max_gaussians >= 0 && max_gaussians <= kMaxSupports, "predict: --max-gaussians ", max_gaussians,
               " is outside [0, ", kMaxSupports, "] (0 = no limit)");
  // Options that only mean something together (a value without its partner would be ignored in silence), before
  // anything loads.
  if (fx > 0) photo_options.intrinsics.fx = fx;
  if (fy > 0) photo_options.intrinsics.fy = fy;
  if (cx >= 0) photo_options.intrinsics.cx = cx;
  if (cy >= 0) photo_options.intrinsics.cy = cy;
  if (hfov > 0) photo_options.intrinsics.hfov = hfov;
  photo_options.seed = static_cast<uint64_t>(seed);
  check_photo_options(photo_options);
  const InputKind kind = input_kind(image_path);
  const std::vector<NamedPath> inputs = {{"--checkpoint", checkpoint},   {"--image", image_path},
                                         {"--depth", depth_path},        {"--prompts", prompts_path},
                                         {"--align-points", align_path}, {"--depth-model", depth_model}};
  if (kind == InputKind::Image) {  // Neither output may be one of the inputs (same path, hard link, symlinked folder).
    refuse_output_over_input("predict", {"--out", out}, inputs);
    refuse_output_over_input("predict", {"--out's camera JSON", camera_sidecar_path(out)}, inputs);
  } else {
    ISPLAT_CHECK(depth_path.empty() && prompts_path.empty() && align_path.empty(),
                 "predict: --depth, --prompts and --align-points hold one photo's data; ",
                 "with a folder, list or video as --image (", image_path, ") give neither");
    ISPLAT_CHECK(!fs::exists(out) || fs::is_directory(out), "predict: --out ", out,
                 " must be a folder when --image is a folder, list or video (", image_path, ")");
  }
  // The merge flags pass the config schema's bounds, with its error naming the key.
  merge = config_from_json<MergeOptions>(config_to_json(merge), "predict's --merge-* flags");
  configure_threads(threads);
  use_precision(precision, "predict: --precision");
  remove_temporaries_on_signal();  // SIGINT/SIGTERM leave neither output nor a temporary behind
  using Clock = std::chrono::steady_clock;
  const auto t_start = Clock::now();

  if (fill_px != -1) sets.push_back(cat("sampler.fill_px=", fill_px));  // the schema refuses other negatives
  if (!depth_model.empty()) sets.insert(sets.end(), {"prior.type=torchscript", "prior.torchscript=" + depth_model});
  if (!depth_path.empty()) sets.push_back("prior.type=dataset");
  if (!prompts_path.empty()) sets.push_back("prior.type=sparse");
  PhotoPredictor predictor(checkpoint, sets);
  Pipeline& pipeline = predictor.pipeline();
  const SamplerOptions configured = pipeline.model()->options.sampler;
  // One photo -> its PLY and camera JSON at `ply_out`. `exif_from`: the file whose EXIF may give the focal length.
  const auto predict_one = [&](const cv::Mat& photo, const std::string& exif_from, const std::string& label,
                               const std::string& ply_out, bool verbose) {
    const int W0 = photo.cols, H0 = photo.rows;
    ErrorContext context("predicting ", label);
    PhotoInput input;
    input.photo = photo;
    input.label = label;
    input.exif_from = exif_from;
    if (!depth_path.empty()) {
      input.depth = read_depth_exr(depth_path).depth;
      input.depth_label = depth_path;
    }
    if (!prompts_path.empty()) {
      const CsvTable t = read_csv(prompts_path);
      ISPLAT_CHECK(t.size() >= 3, prompts_path, ": ", t.size(), " prompts; the sparse prior needs at least 3");
      for (size_t r = 0; r < t.size(); ++r) {  // a prompt off the photo or at no depth contradicts the photo
        const double u = t.number(r, "u"), v = t.number(r, "v"), z = t.number(r, "z");
        ISPLAT_CHECK(u >= 0 && u <= W0 && v >= 0 && v <= H0 && std::isfinite(z) && z > 0, prompts_path, ": row ", r + 1,
                     ": prompt (u ", u, ", v ", v, ", z ", z, ") is off the ", W0, "x", H0,
                     " photo or not at a positive depth");
        input.prompts.push_back({u, v, z});
      }
    }
    PhotoHooks hooks;
    // --max-gaussians: the supports the checkpoint's sampler would place on this photo's prior depth, counted before
    // decoding; above the limit, the sampler places exactly the limit (pruning only removes).
    int64_t would_place = 0;
    bool cap_warned = false;
    hooks.after_prior = [&](PriorOutput& prior, const PhotoFrame& frame) {
      if (max_gaussians <= 0) return;
      would_place =
          sample_supports(prior.depth, prior.valid, prior.K, frame.input.image, configured, frame.input.seed, false)
              .count();
      if (would_place <= max_gaussians) return;
      SamplerOptions& capped = pipeline.model()->options.sampler;
      capped.budget_mode = "fixed";
      capped.budget = max_gaussians;
      if (!capped.has_budget()) {  // pixel mode: area sampling with the lab's edge supports (version 2's) instead
        const SamplerOptions area = model_defaults(2).sampler;
        capped.mode = area.mode, capped.edge_supports = area.edge_supports, capped.image_share = area.image_share;
        capped.pixel_floor = area.pixel_floor, capped.edge_band = area.edge_band;
        if (!cap_warned)
          log_warn("predict: --max-gaussians ", max_gaussians, " is below the ", would_place,
                   " supports the checkpoint's pixel sampler places; area sampling places them instead, a layout the "
                   "model was not trained on");
        cap_warned = true;
      }
    };
    ScaleFit aligned;
    hooks.after_decode = [&](Gaussians& g, const PhotoFrame& frame) {
      if (align_path.empty()) return;  // the evaluator's scoring.align_scale, from the user's points
      const CsvTable t = read_csv(align_path);
      auto samples = torch::empty({static_cast<int64_t>(t.size()), 3});
      for (size_t r = 0; r < t.size(); ++r) {
        samples[r][0] = t.number(r, "u") * frame.width / W0;
        samples[r][1] = t.number(r, "v") * frame.height / H0;
        samples[r][2] = t.number(r, "z");
      }
      aligned = fit_scene_scale(g, to_camera(frame.view), samples);
      ISPLAT_CHECK(aligned.samples > 0, "predict: --align-points ", align_path, ": none of its ", t.size(),
                   " points falls on the predicted surface of ", label);
      g = scale_about_camera(g, to_camera(frame.view), aligned.factor);
    };
    pipeline.model()->options.sampler = configured;
    const PhotoPrediction result = predictor.predict(input, photo_options, hooks);
    pipeline.model()->options.sampler = configured;
    const Prediction& pred = result.prediction;
    ISPLAT_CHECK(max_gaussians <= 0 || pred.gaussians.count() <= max_gaussians, "predict: ", label,
                 ": the sampler placed ", pred.supports.count(), " supports for --max-gaussians ", max_gaussians,
                 " (sampler.mode ", configured.mode, ")");
    const int Wm = result.frame.width, Hm = result.frame.height;
    const View& view = result.frame.view;
    const Gaussians& g = result.gaussians;
    const PruneResult& pruned = result.pruned;
    const int64_t made = result.decoded, outside = result.outside;
    const double prune_ms = result.prune_ms;
    const int64_t faint = pruned.low_opacity;
    ISPLAT_CHECK(g.count() > 0, "predict: no Gaussian is left of ", made, " (", outside, " outside the view, ", faint,
                 " below opacity ", photo_options.prune_opacity, ", ", pruned.low_contribution, " below contribution, ",
                 pruned.merge.removed(), " merged); not writing an empty scene to ", ply_out, " (", label, ")");
    PlyOptions ply;  // what pruning removed travels with the scene
    std::ostringstream pruning;
    pruning << "pruning: decoded " << made << ", outside_view " << outside << ", low_opacity " << faint
            << " (min_opacity " << photo_options.prune_opacity << "), low_contribution " << pruned.low_contribution
            << " (min_contribution " << photo_options.prune_contribution << ", views "
            << (photo_options.prune_contribution > 0 ? photo_options.prune_views : 0) << "), merged_away "
            << pruned.merge.removed() << ", kept " << g.count();
    ply.comments.push_back(pruning.str());
    ply.comments.push_back(cat("working_size ", Wm, "x", Hm, " (photo ", W0, "x", H0, ")"));
    ply.comments.push_back(
        cat("scale_floor_px ", result.scale_floor_px, " (the checkpoint's: ", predictor.trained_floor_px(), ")"));
    if (aligned.samples > 0)
      ply.comments.push_back(
          cat("scale_aligned ", aligned.factor, " (median over ", aligned.samples, " points of ", align_path, ")"));
    {  // Both files new or neither: each is written whole to its temporary, then both are renamed together.
      AtomicPath ply_file(ply_out), camera_file(camera_sidecar_path(ply_out));
      write_ply(ply_file.temp(), g, pipeline.model()->options.composer.linear_rgb, ply);
      write_scene_camera(camera_file.temp(), view, pred.supports.depth.median().item<double>() * aligned.factor);
      commit_together({&camera_file, &ply_file});
    }

    if (!verbose) return g.count();
    std::cout << "photo        " << label << " (" << W0 << "x" << H0 << "), working size " << Wm << "x" << Hm << "\n";
    std::cout << "intrinsics   fx " << std::fixed << std::setprecision(1) << result.frame.intrinsics.fx << " px, "
              << result.frame.intrinsics_source << "\n";
    std::cout << "depth prior  " << pipeline.prior().describe() << "\n";
    if (aligned.samples > 0)
      std::cout << "scale        x" << aligned.factor << " to the units of " << align_path << " (median over "
                << aligned.samples << " points)\n";
    std::cout << "supports     " << pred.supports.count()
              << (max_gaussians > 0 && would_place > max_gaussians
                      ? cat(" (--max-gaussians ", max_gaussians, "; the checkpoint's sampler would place ", would_place,
                            ")")
                      : std::string())
              << "\n";
    std::cout << "Gaussians    " << g.count() << " written of " << made << " decoded (pruned: " << outside
              << " outside the view, " << faint << " below opacity " << std::setprecision(3) << std::defaultfloat
              << photo_options.prune_opacity << ", " << pruned.low_contribution << " below contribution "
              << photo_options.prune_contribution << " over the source and "
              << (photo_options.prune_contribution > 0 ? photo_options.prune_views : 0) << " nearby views, "
              << pruned.merge.removed() << " merged into neighbours)\n";
    if (const Camera source = to_camera(view); source.width * 4 <= max_image_pixels() / (source.height * 4))
      std::cout << "display      " << std::setprecision(2) << std::fixed
                << 100.0 * upscaled_hole_share(g, source, 4.0, RenderOptions{})
                << "% of the source view's centre shows gaps at 4x the working size (" << 4 * Wm << "x" << 4 * Hm
                << "; alpha < 0.5)\n"
                << std::defaultfloat;
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
    std::cout << "wrote        " << fs::absolute(ply_out).string() << "\n             "
              << fs::absolute(camera_sidecar_path(ply_out)).string() << "\n";
    return g.count();
  };

  if (kind == InputKind::Image) {
    predict_one(read_image(image_path), image_path, image_path, out, true);
    return 0;
  }
  // A folder, a list or a video: one PLY and camera JSON per input under --out; complete ones are skipped.
  std::vector<BatchInput> batch =
      kind == InputKind::Video ? video_inputs(image_path, every) : image_inputs(image_path, kind);
  ISPLAT_CHECK(!batch.empty(), "predict: ", image_path, " holds no ", kind == InputKind::Video ? "frame" : "image");
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) fail("predict: --out ", out, ": cannot create the folder: ", ec.message());
  cv::VideoCapture video;
  int64_t video_at = 0;  // the next frame the capture returns
  if (kind == InputKind::Video && !video.open(image_path)) fail(image_path, ": OpenCV cannot read this video");
  int64_t predicted = 0, skipped = 0, written = 0;
  ProgressBar bar("predict", static_cast<int64_t>(batch.size()), kind == InputKind::Video ? "frame" : "image");
  for (const BatchInput& input : batch) {
    const std::string ply_out = (fs::path(out) / (input.name + ".ply")).string();
    refuse_output_over_input("predict", {"--out", ply_out}, {inputs[0], {"--image", input.path}, inputs[1]});
    refuse_output_over_input("predict", {"--out", camera_sidecar_path(ply_out)},
                             {inputs[0], {"--image", input.path}, inputs[1]});
    if (outputs_complete(ply_out)) {
      ++skipped;
      bar.tick();
      continue;
    }
    cv::Mat photo;
    if (kind == InputKind::Video) {
      for (; video_at < input.frame; ++video_at)
        if (!video.grab()) fail(image_path, ": the video ends at frame ", video_at, " before frame ", input.frame);
      cv::Mat bgr;
      if (!video.read(bgr) || bgr.empty()) fail(image_path, ": cannot decode frame ", input.frame);
      ++video_at;
      cv::cvtColor(bgr, photo, cv::COLOR_BGR2RGB);
      photo.convertTo(photo, CV_32FC3, 1.0 / 255.0);
    } else {
      photo = read_image(input.path);
    }
    const std::string label = kind == InputKind::Video ? cat(image_path, " frame ", input.frame) : input.path;
    written += predict_one(photo, kind == InputKind::Video ? std::string() : input.path, label, ply_out, false);
    ++predicted;
    bar.postfix(input.name);
    bar.tick();
  }
  bar.finish();
  std::cout << "predicted    " << predicted << " of " << batch.size() << " inputs (" << written
            << " Gaussians written), " << skipped << " skipped (their PLY and camera JSON were already in " << out
            << ")\n";
  std::cout << "wrote        " << fs::absolute(out).string() << "\n";
  return 0;
}

}  // namespace isplat::cli
