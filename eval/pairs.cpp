// Pair candidates, filters, seeded per-bin draws with per-scene caps, manifest JSON.
#include "eval/pairs.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/config.h"
#include "core/error.h"
#include "core/log.h"
#include "core/progress.h"
#include "io/atomic_file.h"

namespace isplat {

void ProtocolOptions::visit(ConfigVisitor& v) {
  v.field("window", window, "pairs come from windows of this many consecutive views (paper: 10)", Range::at_least(2));
  v.field("min_overlap", min_overlap, "keep pairs whose frustum overlap exceeds this (paper: 0.6)", Range::unit());
  v.field("max_rotation_deg", max_rotation_deg,
          "largest angle between the optical axes (backward-facing pairs are "
          "always dropped)",
          Range::between(0, 180));
  v.field("bin_edges", bin_edges, "baseline bin lower edges in metres; the last bin is open (paper: 0, 0.5, 1, 2)",
          Range::at_least(0));
  v.field("pairs_per_bin", pairs_per_bin, "pairs drawn per bin (paper: 128, so 512 per dataset)", Range::at_least(1));
  v.field("per_scene_cap", per_scene_cap, "most pairs one scene may give to one bin", Range::at_least(1));
  v.field("seed", seed, "seed of the draw", Range::at_least(0));
  v.field("fallback_depth", fallback_depth,
          "overlap depth (m) for frames with neither depth nor COLMAP points3D; 0 = where neighbouring "
          "optical axes converge",
          Range::at_least(0));
}

std::string Manifest::bin_label(int b) const {
  const auto& e = protocol.bin_edges;
  auto num = [](double x) {
    std::ostringstream os;
    os << x;
    return os.str();
  };
  return b + 1 < static_cast<int>(e.size()) ? cat("[", num(e[b]), ",", num(e[b + 1]), ")")
                                            : cat("[", num(e[b]), ",inf)");
}

namespace {
double axis_angle_deg(const View& a, const View& b) {
  const Eigen::Vector3d za = a.T_cw.block<1, 3>(2, 0).transpose(), zb = b.T_cw.block<1, 3>(2, 0).transpose();
  return std::acos(std::clamp(za.dot(zb), -1.0, 1.0)) * 180.0 / M_PI;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

constexpr int kGrid = 32;          // cells across of a proxy depth map
constexpr size_t kMinPoints = 20;  // observed points for a per-view map

DepthMap constant_depth(const Intrinsics& intr, double z) {
  const int gy = std::max(1, kGrid * intr.height / std::max(1, intr.width));
  return {cv::Mat(gy, kGrid, CV_32F, cv::Scalar(z)), cv::Mat(gy, kGrid, CV_8U, cv::Scalar(1)), 0};
}

// Median depth along each optical axis at which it passes closest to a neighbour's axis (both in front,
// axes at least 5 degrees apart): for orbits the object distance, for walks what the cameras look at.
double axes_convergence_depth(const Sequence& seq, int64_t window) {
  std::vector<double> depths;
  for (size_t i = 0; i < seq.frames.size(); ++i)
    for (size_t j = i + 1; j < std::min(seq.frames.size(), i + static_cast<size_t>(window)); ++j) {
      const View &a = seq.frames[i].view, &b = seq.frames[j].view;
      const Eigen::Vector3d ca = camera_center(a.T_cw), cb = camera_center(b.T_cw);
      const Eigen::Vector3d da = a.T_cw.block<1, 3>(2, 0).transpose(), db = b.T_cw.block<1, 3>(2, 0).transpose();
      const double c = da.dot(db);
      if (c > std::cos(5.0 * M_PI / 180.0)) continue;
      const Eigen::Vector3d w = ca - cb;
      const double denom = 1 - c * c, ta = (c * db.dot(w) - da.dot(w)) / denom,
                   tb = (db.dot(w) - c * da.dot(w)) / denom;
      if (ta > 0 && tb > 0) depths.push_back(ta), depths.push_back(tb);
    }
  return depths.size() >= 3 ? median(depths) : 0.0;
}
}  // namespace

OverlapDepthSource::OverlapDepthSource(const Sequence& sequence, const ColmapModel* model, const ProtocolOptions& o)
    : sequence_(sequence), points_(sequence.frames.size()) {
  bool needed = false;
  for (const auto& f : sequence.frames) needed |= f.depth == DepthSource::None;
  if (!needed) return;
  std::vector<double> all;
  if (model) {
    std::map<std::string, const ColmapImage*> by_name;
    for (const auto& [id, img] : model->images) by_name[img.name] = &img;
    for (size_t k = 0; k < sequence.frames.size(); ++k) {
      const FrameRecord& f = sequence.frames[k];
      const ColmapImage* img = nullptr;
      for (const auto& [name, im] : by_name)  // COLMAP names are relative to the image folder
        if (f.image_path.size() >= name.size() + 1 &&
            f.image_path.compare(f.image_path.size() - name.size() - 1, std::string::npos, "/" + name) == 0)
          img = im;
      if (!img) continue;
      for (int64_t pid : img->point3D_ids) {  // the points this image observes (its track), not just any in view
        if (pid < 0) continue;
        auto it = model->points.find(pid);
        if (it == model->points.end()) continue;
        Eigen::Vector2d uv;
        double z = 0;
        if (!f.view.project(it->second.xyz, uv, z) || !(z > 0)) continue;
        if (uv.x() < 0 || uv.y() < 0 || uv.x() >= f.view.intr.width || uv.y() >= f.view.intr.height) continue;
        points_[k].emplace_back(uv.x(), uv.y(), z);
        all.push_back(z);
      }
    }
  }
  scene_depth_ = median(all);
  if (o.fallback_depth > 0) {
    fallback_ = o.fallback_depth, fallback_kind_ = "fixed";
  } else {
    fallback_ = axes_convergence_depth(sequence, o.window), fallback_kind_ = "camera-axes";
  }
}

OverlapDepth OverlapDepthSource::for_frame(size_t index) const {
  const FrameRecord& f = sequence_.frames[index];
  const Intrinsics& intr = f.view.intr;
  const auto& pts = points_[index];
  if (pts.size() >= kMinPoints) {
    std::vector<double> zs;
    for (const auto& p : pts) zs.push_back(p.z());
    OverlapDepth out{constant_depth(intr, median(zs)), "points3d"};
    cv::Mat& d = out.map.depth;
    std::vector<std::vector<double>> cells(static_cast<size_t>(d.rows * d.cols));
    for (const auto& p : pts) {
      const int j = std::min(d.cols - 1, static_cast<int>(p.x() * d.cols / intr.width));
      const int i = std::min(d.rows - 1, static_cast<int>(p.y() * d.rows / intr.height));
      cells[static_cast<size_t>(i * d.cols + j)].push_back(p.z());
    }
    for (int i = 0; i < d.rows; ++i)
      for (int j = 0; j < d.cols; ++j)
        if (!cells[static_cast<size_t>(i * d.cols + j)].empty())
          d.at<float>(i, j) = static_cast<float>(median(cells[static_cast<size_t>(i * d.cols + j)]));
    return out;
  }
  if (scene_depth_ > 0) return {constant_depth(intr, scene_depth_), "scene-points3d"};
  if (fallback_ > 0) return {constant_depth(intr, fallback_), fallback_kind_};
  fail("pairs: ", sequence_.id(), " frame ", f.name,
       " has no depth, no COLMAP points3D, and its cameras' optical axes do not converge; set "
       "protocol.fallback_depth to the scene's typical depth in metres");
}

Manifest draw_manifest(const std::string& dataset, const std::vector<Sequence>& sequences, const ProtocolOptions& o,
                       const std::vector<ColmapModel>& models) {
  ISPLAT_CHECK(!o.bin_edges.empty() && std::is_sorted(o.bin_edges.begin(), o.bin_edges.end()),
               "protocol.bin_edges must be a non-empty increasing list");
  Manifest m;
  m.dataset = dataset;
  m.protocol = o;
  const size_t bins = o.bin_edges.size();
  std::vector<std::vector<Pair>> candidates(bins);
  int64_t frames = 0;
  for (const auto& s : sequences) frames += static_cast<int64_t>(s.frames.size());
  ProgressBar bar(cat("pairs ", dataset), frames, "frame");
  for (size_t si = 0; si < sequences.size(); ++si) {
    const Sequence& seq = sequences[si];
    if (seq.frames.size() < 2) {
      log_warn("pairs: ", dataset, "/", seq.id(), " has ", seq.frames.size(), " frame(s); no pairs");
      bar.tick(static_cast<int64_t>(seq.frames.size()));
      continue;
    }
    const OverlapDepthSource proxies(seq, si < models.size() ? &models[si] : nullptr, o);
    for (size_t s = 0; s < seq.frames.size(); ++s, bar.tick()) {
      OverlapDepth od;
      if (seq.frames[s].depth != DepthSource::None) {
        od = {load_frame(seq, s).depth, "dataset"};
      } else {
        od = proxies.for_frame(s);
      }
      ++m.overlap_depth[od.kind];
      const View& sv = seq.frames[s].view;
      const size_t lo = s >= static_cast<size_t>(o.window - 1) ? s - (o.window - 1) : 0;
      const size_t hi = std::min(seq.frames.size() - 1, s + static_cast<size_t>(o.window - 1));
      for (size_t t = lo; t <= hi; ++t) {
        if (t == s) continue;
        const View& tv = seq.frames[t].view;
        const double rot = axis_angle_deg(sv, tv);
        if (rot >= 90.0 || rot > o.max_rotation_deg) {
          ++m.rejected["rotation"];
          continue;
        }
        const double ov = frustum_overlap(sv, od.map, tv);
        if (!(ov > o.min_overlap)) {
          ++m.rejected["overlap"];
          continue;
        }
        Pair p;
        p.dataset = dataset;
        p.scene = seq.scene;
        p.sequence = seq.name;
        p.sequence_index = si;
        p.source = s;
        p.target = t;
        p.source_name = seq.frames[s].name;
        p.target_name = seq.frames[t].name;
        p.baseline = baseline(sv, tv);
        p.overlap_depth = od.kind;
        p.overlap = ov;
        p.rotation_deg = rot;
        p.bin = static_cast<int>(std::upper_bound(o.bin_edges.begin(), o.bin_edges.end(), p.baseline) -
                                 o.bin_edges.begin()) -
                1;
        if (p.bin >= 0)
          candidates[static_cast<size_t>(p.bin)].push_back(p);
        else
          ++m.rejected["outside bins"];
      }
    }
  }
  bar.finish();
  std::mt19937_64 rng(static_cast<uint64_t>(o.seed));
  for (size_t b = 0; b < bins; ++b) {
    auto& c = candidates[b];
    m.bin_candidates.push_back(static_cast<int64_t>(c.size()));
    std::shuffle(c.begin(), c.end(), rng);
    std::map<std::string, int64_t> per_scene;
    int64_t taken = 0;
    for (const auto& p : c) {
      if (taken >= o.pairs_per_bin) break;
      if (per_scene[p.scene] >= o.per_scene_cap) {
        ++m.rejected["per-scene cap"];
        continue;
      }
      ++per_scene[p.scene];
      m.pairs.push_back(p);
      ++taken;
    }
    m.bin_counts.push_back(taken);
  }
  for (size_t b = 0; b < bins; ++b)
    if (m.bin_counts[b] < o.pairs_per_bin)
      log_warn("pairs: ", dataset, " bin ", m.bin_label(static_cast<int>(b)), " has ", m.bin_counts[b], " of ",
               o.pairs_per_bin, " pairs; not padded. ", m.shortfall_reason(static_cast<int>(b)));
  return m;
}

std::string Manifest::shortfall_reason(int b) const {
  const int64_t candidates = bin_candidates.at(static_cast<size_t>(b));
  auto count = [&](const char* k) {
    auto it = rejected.find(k);
    return it == rejected.end() ? int64_t{0} : it->second;
  };
  if (pairs.empty() && count("rotation") + count("overlap") + count("outside bins") == 0)
    return "No source frame gave a candidate pair: the sequences have fewer than 2 frames each.";
  if (candidates > 0)
    return cat(candidates,
               " candidates passed the filters; the per-scene cap (protocol.per_scene_cap = ", protocol.per_scene_cap,
               ") or the dataset's size limits the draw.");
  std::string why = cat("No pair that passes the filters has a baseline in ", bin_label(b),
                        " (cameras within a window of ", protocol.window, " views are never that far apart");
  why += cat("); across all bins ", count("overlap"),
             " pairs failed the overlap test (protocol.min_overlap = ", protocol.min_overlap, ") and ",
             count("rotation"), " the rotation test (protocol.max_rotation_deg = ", protocol.max_rotation_deg, ").");
  if (!overlap_depth.empty() && !overlap_depth.count("dataset"))
    why += " The overlap used proxy depth (no dataset depth); see overlap_depth in the manifest.";
  return why;
}

nlohmann::ordered_json Manifest::to_json() const {
  nlohmann::ordered_json j;
  j["dataset"] = dataset;
  j["seed"] = protocol.seed;
  j["protocol"] = config_to_json(protocol);
  j["overlap_depth"] = overlap_depth;
  j["rejected"] = rejected;
  if (!dataset_fingerprint.is_null()) j["dataset_fingerprint"] = dataset_fingerprint;
  j["bins"] = nlohmann::ordered_json::array();
  for (size_t b = 0; b < bin_counts.size(); ++b)
    j["bins"].push_back({{"bin", bin_label(static_cast<int>(b))},
                         {"requested", protocol.pairs_per_bin},
                         {"filled", bin_counts[b]},
                         {"candidates", bin_candidates[b]}});
  j["pairs"] = nlohmann::ordered_json::array();
  for (const auto& p : pairs)
    j["pairs"].push_back({{"dataset", p.dataset},
                          {"scene", p.scene},
                          {"sequence", p.sequence},
                          {"sequence_index", p.sequence_index},
                          {"source", p.source_name},
                          {"target", p.target_name},
                          {"source_index", p.source},
                          {"target_index", p.target},
                          {"baseline", p.baseline},
                          {"overlap", p.overlap},
                          {"rotation_deg", p.rotation_deg},
                          {"bin", p.bin},
                          {"overlap_depth", p.overlap_depth},
                          {"seed", protocol.seed}});
  return j;
}

Manifest Manifest::from_json(const nlohmann::json& j, const std::string& source) {
  Manifest m;
  try {
    m.dataset = j.at("dataset").get<std::string>();
    m.protocol = config_from_json<ProtocolOptions>(j.at("protocol"), source);
    if (j.contains("overlap_depth")) m.overlap_depth = j.at("overlap_depth").get<std::map<std::string, int64_t>>();
    if (j.contains("rejected")) m.rejected = j.at("rejected").get<std::map<std::string, int64_t>>();
    if (j.contains("dataset_fingerprint")) m.dataset_fingerprint = j.at("dataset_fingerprint");
    for (const auto& b : j.at("bins")) {
      m.bin_counts.push_back(b.at("filled").get<int64_t>());
      m.bin_candidates.push_back(b.at("candidates").get<int64_t>());
    }
    for (const auto& e : j.at("pairs")) {
      Pair p;
      p.dataset = e.at("dataset").get<std::string>();
      p.scene = e.at("scene").get<std::string>();
      p.sequence = e.at("sequence").get<std::string>();
      p.sequence_index = e.at("sequence_index").get<size_t>();
      p.source_name = e.at("source").get<std::string>();
      p.target_name = e.at("target").get<std::string>();
      p.source = e.at("source_index").get<size_t>();
      p.target = e.at("target_index").get<size_t>();
      p.baseline = e.at("baseline").get<double>();
      p.overlap = e.at("overlap").get<double>();
      p.rotation_deg = e.at("rotation_deg").get<double>();
      const int64_t bin = e.at("bin").get<int64_t>();
      p.bin = bin >= 0 && bin <= 1000 ? static_cast<int>(bin) : -1;  // -1 fails the range check below
      p.overlap_depth = e.value("overlap_depth", std::string("dataset"));
      if (p.bin < 0 || p.bin >= static_cast<int>(m.bin_counts.size()) || !std::isfinite(p.baseline) || p.baseline < 0)
        fail(source, ": manifest pair ", m.pairs.size(), " has bin ", p.bin, " and baseline ", p.baseline,
             "; expected a bin in [0, ", m.bin_counts.size(), ") and a finite baseline >= 0");
      m.pairs.push_back(p);
    }
  } catch (const nlohmann::json::exception& e) {
    fail(source, ": malformed manifest: ", e.what());
  }
  return m;
}

void write_manifest(const std::string& path, const Manifest& m) {
  write_file_atomic(path, m.to_json().dump(2) + "\n");
}

Manifest read_manifest(const std::string& path) {
  return Manifest::from_json(read_json_file(path), path);
}

std::string motion_type(const std::array<double, 3>& t, double rotation_deg, double median_depth, double half_edge) {
  ISPLAT_CHECK(median_depth > 0 && std::isfinite(median_depth), "motion_type: median depth ", median_depth,
               " is not positive");
  ISPLAT_CHECK(half_edge > 0 && std::isfinite(half_edge), "motion_type: half_edge ", half_edge, " is not positive");
  const double lateral = std::hypot(t[0], t[1]) / median_depth;
  const double forward = half_edge * std::abs(t[2]) / median_depth;
  const double rotation = rotation_deg * M_PI / 180.0;
  if (rotation >= lateral && rotation >= forward) return "rotation";
  return lateral >= forward ? "lateral" : "forward";
}

}  // namespace isplat
