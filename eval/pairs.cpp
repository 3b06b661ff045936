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
}  // namespace

Manifest select_pairs(const std::string& dataset, const std::vector<Sequence>& sequences, const ProtocolOptions& o) {
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
    for (size_t s = 0; s < seq.frames.size(); ++s, bar.tick()) {
      if (seq.frames[s].depth == DepthSource::None) continue;  // overlap needs the source depth
      const LoadedFrame src = load_frame(seq, s);
      const size_t lo = s >= static_cast<size_t>(o.window - 1) ? s - (o.window - 1) : 0;
      const size_t hi = std::min(seq.frames.size() - 1, s + static_cast<size_t>(o.window - 1));
      for (size_t t = lo; t <= hi; ++t) {
        if (t == s) continue;
        const View& tv = seq.frames[t].view;
        const double rot = axis_angle_deg(src.view, tv);
        if (rot >= 90.0 || rot > o.max_rotation_deg) continue;
        const double ov = frustum_overlap(src.view, src.depth, tv);
        if (!(ov > o.min_overlap)) continue;
        Pair p;
        p.dataset = dataset;
        p.scene = seq.scene;
        p.sequence = seq.name;
        p.sequence_index = si;
        p.source = s;
        p.target = t;
        p.source_name = seq.frames[s].name;
        p.target_name = seq.frames[t].name;
        p.baseline = baseline(src.view, tv);
        p.overlap = ov;
        p.rotation_deg = rot;
        p.bin = static_cast<int>(std::upper_bound(o.bin_edges.begin(), o.bin_edges.end(), p.baseline) -
                                 o.bin_edges.begin()) -
                1;
        if (p.bin >= 0) candidates[static_cast<size_t>(p.bin)].push_back(p);
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
      if (per_scene[p.scene] >= o.per_scene_cap) continue;
      ++per_scene[p.scene];
      m.pairs.push_back(p);
      ++taken;
    }
    m.bin_counts.push_back(taken);
    if (taken < o.pairs_per_bin)
      log_warn("pairs: ", dataset, " bin ", m.bin_label(static_cast<int>(b)), " has ", taken, " of ", o.pairs_per_bin,
               " pairs (", c.size(), " candidates pass the filters; per-scene cap ", o.per_scene_cap, "); not padded");
  }
  return m;
}

nlohmann::ordered_json Manifest::to_json() const {
  nlohmann::ordered_json j;
  j["dataset"] = dataset;
  j["seed"] = protocol.seed;
  j["protocol"] = config_to_json(protocol);
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
                          {"seed", protocol.seed}});
  return j;
}

Manifest Manifest::from_json(const nlohmann::json& j, const std::string& source) {
  Manifest m;
  try {
    m.dataset = j.at("dataset").get<std::string>();
    m.protocol = config_from_json<ProtocolOptions>(j.at("protocol"), source);
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
      p.bin = e.at("bin").get<int>();
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

}  // namespace isplat
