// COLMAP model I/O (text + binary), camera-model table, and scene -> Sequence conversion.
#include "data/colmap.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/error.h"
#include "core/parse.h"
#include "core/runtime.h"
#include "io/atomic_file.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {

const ColmapModelInfo kModels[] = {
    {0, "SIMPLE_PINHOLE", 3},
    {1, "PINHOLE", 4},
    {2, "SIMPLE_RADIAL", 4},
    {3, "RADIAL", 5},
    {4, "OPENCV", 8},
    {5, "OPENCV_FISHEYE", 8},
    {6, "FULL_OPENCV", 12},
    {7, "FOV", 5},
    {8, "SIMPLE_RADIAL_FISHEYE", 4},
    {9, "RADIAL_FISHEYE", 5},
    {10, "THIN_PRISM_FISHEYE", 12},
    {11, "RAD_TAN_THIN_PRISM_FISHEYE", 16},
};

// ---- text helpers
std::vector<std::string> split_ws(const std::string& line) {
  std::istringstream is(line);
  std::vector<std::string> out;
  std::string tok;
  while (is >> tok) out.push_back(tok);
  return out;
}

double to_double(const std::string& s, const std::string& where) {
  const auto v = parse_double(s);
  if (!v) fail(where, ": expected a number, got '", s, "'");
  return *v;
}

int64_t to_int(const std::string& s, const std::string& where) {
  const auto v = parse_int(s);
  if (!v) fail(where, ": expected an integer, got '", s, "'");
  return *v;
}

std::vector<std::string> read_lines(const std::string& path) {
  std::istringstream in(read_file_bytes(path));
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(line);
  }
  return lines;
}

// Where each id and image name was first seen ("line 3", "entry 0"): a second definition is a contradiction the
// model cannot settle (which pose is right?), so it is an error naming both places, never a silent overwrite.
class FirstSeen {
 public:
  FirstSeen(std::string file, const char* what) : file_(std::move(file)), what_(what) {}
  template <class Key>
  void add(const Key& key, const std::string& where, std::map<Key, std::string>& seen) const {
    const auto [it, fresh] = seen.emplace(key, where);
    if (!fresh) fail(file_, ": ", what_, " ", key, " is defined twice (", it->second, " and ", where, ")");
  }

 private:
  std::string file_;
  const char* what_;
};

// The NAME field of an images.txt line: everything after the ninth field, as written (COLMAP keeps inner spaces,
// repeated or not); trailing blanks are an editor's, not the name's.
std::string rest_after_fields(const std::string& line, int fields) {
  size_t p = 0;
  for (int f = 0; f < fields; ++f) {
    p = line.find_first_not_of(" \t", p);
    p = line.find_first_of(" \t", p);
    if (p == std::string::npos) return "";
  }
  p = line.find_first_not_of(" \t", p);
  if (p == std::string::npos) return "";
  return line.substr(p, line.find_last_not_of(" \t") - p + 1);
}

bool is_comment_or_blank(const std::string& line) {
  const auto p = line.find_first_not_of(" \t");
  return p == std::string::npos || line[p] == '#';
}

// Models with one focal length store f, cx, cy first; the others fx, fy, cx, cy.
bool single_focal(int64_t model_id) {
  return model_id == 0 || model_id == 2 || model_id == 3 || model_id == 8 || model_id == 9;
}

void check_params(const ColmapCamera& c, const std::string& where) {
  const ColmapModelInfo* m = colmap_model_by_id(c.model_id);
  if (!m) fail(where, ": camera ", c.id, " has unknown model id ", c.model_id);
  if (static_cast<int>(c.params.size()) != m->num_params)
    fail(where, ": camera ", c.id, " model ", m->name, " needs ", m->num_params, " parameters, got ", c.params.size());
  if (c.width <= 0 || c.height <= 0 || c.width > max_image_pixels() / c.height)
    fail(where, ": camera ", c.id, " has size ", c.width, "x", c.height);
  for (double p : c.params)
    if (!std::isfinite(p)) fail(where, ": camera ", c.id, " has a non-finite parameter");
  // A focal length of 0 projects everything to the centre: every pair would fail the overlap test silently.
  const bool ok = c.params[0] > 0 && (single_focal(c.model_id) || c.params[1] > 0);
  if (!ok) fail(where, ": camera ", c.id, " has a focal length that is not positive");
}

// ---- binary helpers
class BinReader {
 public:
  explicit BinReader(const std::string& path) : path_(path), data_(read_file_bytes(path)) {}
  template <class T>
  T get() {
    if (pos_ + sizeof(T) > data_.size()) fail(path_, ": truncated at byte ", pos_, " (file has ", data_.size(), ")");
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  std::string cstring() {
    const size_t end = data_.find('\0', pos_);
    if (end == std::string::npos) fail(path_, ": truncated string at byte ", pos_);
    std::string s = data_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return s;
  }
  void check_count(uint64_t count, size_t min_bytes_each) const {
    if (count > (data_.size() - pos_) / std::max<size_t>(1, min_bytes_each) + 1)
      fail(path_, ": count ", count, " at byte ", pos_, " exceeds the file size (corrupt header)");
  }
  bool done() const { return pos_ == data_.size(); }
  const std::string& path() const { return path_; }

 private:
  std::string path_, data_;
  size_t pos_ = 0;
};

std::string model_dir_file(const std::string& dir, const std::string& name) {
  return (fs::path(dir) / name).string();
}

void check_references(const ColmapModel& m, const std::string& dir) {
  for (const auto& [id, img] : m.images)
    if (!m.cameras.count(img.camera_id))
      fail(dir, ": image ", id, " (", img.name, ") refers to camera ", img.camera_id,
           ", which cameras does not define");
}

}  // namespace

const ColmapModelInfo* colmap_model_by_id(int id) {
  for (const auto& m : kModels)
    if (m.id == id) return &m;
  return nullptr;
}

const ColmapModelInfo* colmap_model_by_name(const std::string& name) {
  for (const auto& m : kModels)
    if (name == m.name) return &m;
  return nullptr;
}

ColmapModel read_colmap_text(const std::string& dir) {
  ColmapModel m;
  {
    const std::string path = model_dir_file(dir, "cameras.txt");
    std::map<int64_t, std::string> camera_lines;
    const auto lines = read_lines(path);
    for (size_t i = 0; i < lines.size(); ++i) {
      if (is_comment_or_blank(lines[i])) continue;
      const std::string where = cat(path, ":", i + 1);
      const auto t = split_ws(lines[i]);
      if (t.size() < 4) fail(where, ": expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS...");
      ColmapCamera c;
      c.id = to_int(t[0], where);
      const ColmapModelInfo* info = colmap_model_by_name(t[1]);
      if (!info) fail(where, ": unknown camera model '", t[1], "'");
      c.model_id = info->id;
      c.width = to_int(t[2], where);
      c.height = to_int(t[3], where);
      for (size_t k = 4; k < t.size(); ++k) c.params.push_back(to_double(t[k], where));
      check_params(c, where);
      FirstSeen(path, "camera id").add(c.id, cat("line ", i + 1), camera_lines);
      m.cameras[c.id] = c;
    }
  }
  {
    const std::string path = model_dir_file(dir, "images.txt");
    std::map<int64_t, std::string> id_lines;
    std::map<std::string, std::string> name_lines;
    const auto lines = read_lines(path);
    for (size_t i = 0; i < lines.size(); ++i) {
      if (is_comment_or_blank(lines[i])) continue;
      const std::string where = cat(path, ":", i + 1);
      const auto t = split_ws(lines[i]);
      if (t.size() < 10) fail(where, ": expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME");
      ColmapImage img;
      img.id = to_int(t[0], where);
      for (int k = 0; k < 4; ++k) img.qvec[k] = to_double(t[1 + k], where);
      for (int k = 0; k < 3; ++k) img.tvec[k] = to_double(t[5 + k], where);
      img.camera_id = to_int(t[8], where);
      img.name = rest_after_fields(lines[i], 9);  // names may contain spaces, repeated ones too
      // The next line (possibly empty) lists X Y POINT3D_ID triples.
      if (i + 1 < lines.size()) {
        const auto p = split_ws(lines[++i]);
        if (p.size() % 3 != 0) fail(cat(path, ":", i + 1), ": POINTS2D must be X Y POINT3D_ID triples");
        for (size_t k = 0; k < p.size(); k += 3) {
          img.xys.emplace_back(to_double(p[k], where), to_double(p[k + 1], where));
          img.point3D_ids.push_back(to_int(p[k + 2], where));
        }
      }
      const std::string line_no = cat("line ", where.substr(path.size() + 1));  // the image's line, not its points'
      FirstSeen(path, "image id").add(img.id, line_no, id_lines);
      FirstSeen(path, "image name").add(cat("'", img.name, "'"), line_no, name_lines);
      m.images[img.id] = img;
    }
  }
  {
    const std::string path = model_dir_file(dir, "points3D.txt");
    std::map<int64_t, std::string> point_lines;
    if (fs::exists(path)) {
      const auto lines = read_lines(path);
      for (size_t i = 0; i < lines.size(); ++i) {
        if (is_comment_or_blank(lines[i])) continue;
        const std::string where = cat(path, ":", i + 1);
        const auto t = split_ws(lines[i]);
        if (t.size() < 8 || (t.size() - 8) % 2 != 0) fail(where, ": expected POINT3D_ID X Y Z R G B ERROR TRACK...");
        ColmapPoint p;
        p.id = to_int(t[0], where);
        for (int k = 0; k < 3; ++k) p.xyz[k] = to_double(t[1 + k], where);
        for (int k = 0; k < 3; ++k) p.rgb[k] = static_cast<uint8_t>(to_int(t[4 + k], where));
        p.error = to_double(t[7], where);
        for (size_t k = 8; k < t.size(); k += 2) p.track.emplace_back(to_int(t[k], where), to_int(t[k + 1], where));
        FirstSeen(path, "point id").add(p.id, cat("line ", i + 1), point_lines);
        m.points[p.id] = p;
      }
    }
  }
  check_references(m, dir);
  return m;
}

ColmapModel read_colmap_binary(const std::string& dir) {
  ColmapModel m;
  {
    BinReader r(model_dir_file(dir, "cameras.bin"));
    const uint64_t n = r.get<uint64_t>();
    r.check_count(n, 24);
    std::map<int64_t, std::string> seen;
    for (uint64_t i = 0; i < n; ++i) {
      ColmapCamera c;
      c.id = r.get<uint32_t>();
      c.model_id = r.get<int32_t>();
      c.width = static_cast<int64_t>(r.get<uint64_t>());
      c.height = static_cast<int64_t>(r.get<uint64_t>());
      const ColmapModelInfo* info = colmap_model_by_id(c.model_id);
      if (!info) fail(r.path(), ": camera ", c.id, " has unknown model id ", c.model_id);
      for (int k = 0; k < info->num_params; ++k) c.params.push_back(r.get<double>());
      check_params(c, r.path());
      FirstSeen(r.path(), "camera id").add(c.id, cat("entry ", i), seen);
      m.cameras[c.id] = c;
    }
    if (!r.done()) fail(r.path(), ": trailing bytes after ", n, " cameras");
  }
  {
    BinReader r(model_dir_file(dir, "images.bin"));
    const uint64_t n = r.get<uint64_t>();
    r.check_count(n, 64);
    std::map<int64_t, std::string> ids;
    std::map<std::string, std::string> names;
    for (uint64_t i = 0; i < n; ++i) {
      ColmapImage img;
      img.id = r.get<uint32_t>();
      for (int k = 0; k < 4; ++k) img.qvec[k] = r.get<double>();
      for (int k = 0; k < 3; ++k) img.tvec[k] = r.get<double>();
      img.camera_id = r.get<uint32_t>();
      img.name = r.cstring();
      const uint64_t np = r.get<uint64_t>();
      r.check_count(np, 24);
      for (uint64_t k = 0; k < np; ++k) {
        const double x = r.get<double>(), y = r.get<double>();
        img.xys.emplace_back(x, y);
        img.point3D_ids.push_back(r.get<int64_t>());
      }
      FirstSeen(r.path(), "image id").add(img.id, cat("entry ", i), ids);
      FirstSeen(r.path(), "image name").add(cat("'", img.name, "'"), cat("entry ", i), names);
      m.images[img.id] = img;
    }
    if (!r.done()) fail(r.path(), ": trailing bytes after ", n, " images");
  }
  const std::string ppath = model_dir_file(dir, "points3D.bin");
  if (fs::exists(ppath)) {
    BinReader r(ppath);
    const uint64_t n = r.get<uint64_t>();
    r.check_count(n, 43);
    std::map<int64_t, std::string> seen;
    for (uint64_t i = 0; i < n; ++i) {
      ColmapPoint p;
      p.id = static_cast<int64_t>(r.get<uint64_t>());
      for (int k = 0; k < 3; ++k) p.xyz[k] = r.get<double>();
      for (int k = 0; k < 3; ++k) p.rgb[k] = r.get<uint8_t>();
      p.error = r.get<double>();
      const uint64_t len = r.get<uint64_t>();
      r.check_count(len, 8);
      for (uint64_t k = 0; k < len; ++k) {
        const int64_t image_id = r.get<uint32_t>();
        p.track.emplace_back(image_id, r.get<uint32_t>());
      }
      FirstSeen(r.path(), "point id").add(p.id, cat("entry ", i), seen);
      m.points[p.id] = p;
    }
    if (!r.done()) fail(r.path(), ": trailing bytes after ", n, " points");
  }
  check_references(m, dir);
  return m;
}

ColmapModel read_colmap(const std::string& dir) {
  if (fs::exists(fs::path(dir) / "cameras.bin")) return read_colmap_binary(dir);
  if (fs::exists(fs::path(dir) / "cameras.txt")) return read_colmap_text(dir);
  fail(dir, ": no COLMAP model (cameras.bin or cameras.txt) in this folder");
}

Intrinsics colmap_intrinsics(const ColmapCamera& c, std::vector<double>& distortion) {
  check_params(c, "COLMAP");
  const ColmapModelInfo* info = colmap_model_by_id(c.model_id);
  const auto& p = c.params;
  const bool single_f = single_focal(c.model_id);
  const size_t first_extra = single_f ? 3 : 4;
  const Intrinsics intr = single_f ? Intrinsics{p[0], p[0], p[1], p[2], int(c.width), int(c.height)}
                                   : Intrinsics{p[0], p[1], p[2], p[3], int(c.width), int(c.height)};
  const std::vector<double> extra(p.begin() + first_extra, p.end());
  distortion.clear();
  switch (c.model_id) {  // the models OpenCV can undistort, in its coefficient order
    case 2:
      distortion = {extra[0], 0, 0, 0};
      break;
    case 3:
      distortion = {extra[0], extra[1], 0, 0};
      break;
    case 4:
      distortion = extra;
      break;
    case 6:
      distortion = extra;
      break;
    default:
      for (double x : extra)
        if (x != 0.0)
          fail("COLMAP camera ", c.id, ": model ", info->name,
               " has non-zero distortion that OpenCV cannot undo here; run colmap image_undistorter first");
  }
  if (std::all_of(distortion.begin(), distortion.end(), [](double x) { return x == 0.0; })) distortion.clear();
  return intr;
}

Sequence colmap_sequence(const std::string& scene_dir, const std::string& dataset, const ColmapSceneLayout& layout) {
  fs::path sparse = fs::path(scene_dir) / layout.sparse_dir;
  if (!fs::exists(sparse)) sparse = fs::path(scene_dir) / "sparse";
  const ColmapModel model = read_colmap(sparse.string());
  if (model.images.empty()) fail(sparse.string(), ": the COLMAP model has no images (empty sequence)");
  std::vector<const ColmapImage*> images;
  for (const auto& [id, img] : model.images) images.push_back(&img);
  std::sort(images.begin(), images.end(), [](const ColmapImage* a, const ColmapImage* b) { return a->name < b->name; });
  Sequence seq;
  seq.dataset = dataset;
  seq.scene = fs::path(scene_dir).filename().string();
  seq.name = "colmap";
  const DepthSource depth_kind = layout.depth_format == "exr"           ? DepthSource::PlanarExr
                                 : layout.depth_format == "png16_mm"    ? DepthSource::Png16Millimetres
                                 : layout.depth_format == "raw_float32" ? DepthSource::RawFloat32
                                                                        : DepthSource::None;
  if (depth_kind == DepthSource::None && layout.depth_format != "none")
    fail(scene_dir, ": unknown depth format '", layout.depth_format, "' (exr | png16_mm | raw_float32 | none)");
  for (const ColmapImage* img : images) {
    FrameRecord f;
    f.name = seq.scene + "/" + img->name;
    f.image_path = (fs::path(scene_dir) / layout.images_dir / img->name).string();
    if (!fs::exists(f.image_path))
      fail(sparse.string(), ": images names '", img->name, "' but ", f.image_path, " does not exist");
    const ColmapCamera& cam = model.cameras.at(img->camera_id);
    f.view.intr = colmap_intrinsics(cam, f.distortion);
    if (!f.distortion.empty() && !layout.allow_undistort)
      fail(sparse.string(), ": camera ", cam.id, " (", colmap_model_by_id(cam.model_id)->name,
           ") is distorted and undistortion is off");
    f.view.T_cw = pose_from_colmap(img->qvec, img->tvec);
    if (!f.view.T_cw.allFinite() || img->qvec.norm() < 1e-9)
      fail(sparse.string(), ": image '", img->name, "' has a pose that is not finite (or a zero quaternion)");
    if (depth_kind != DepthSource::None) {
      std::string name = img->name;
      if (!layout.depth_replace_from.empty()) {
        const auto pos = name.find(layout.depth_replace_from);
        if (pos != std::string::npos) name.replace(pos, layout.depth_replace_from.size(), layout.depth_replace_to);
      }
      const fs::path dpath =
          fs::path(scene_dir) / layout.depth_dir /
          (depth_kind == DepthSource::RawFloat32 ? name + layout.depth_suffix
                                                 : fs::path(name).replace_extension("").string() + layout.depth_suffix);
      if (fs::exists(dpath)) {
        f.depth_path = dpath.string();
        f.depth = depth_kind;
      }
    }
    seq.frames.push_back(std::move(f));
  }
  return seq;
}

std::vector<Eigen::Vector3d> colmap_sparse_depth(const ColmapModel& model, const View& view) {
  std::vector<Eigen::Vector3d> out;
  for (const auto& [id, p] : model.points) {
    Eigen::Vector2d uv;
    double z = 0;
    if (!view.project(p.xyz, uv, z)) continue;
    if (uv.x() < 0 || uv.y() < 0 || uv.x() >= view.intr.width || uv.y() >= view.intr.height) continue;
    out.emplace_back(uv.x(), uv.y(), z);
  }
  return out;
}

}  // namespace isplat
