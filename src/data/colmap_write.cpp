// COLMAP model writing, text and binary, in COLMAP's own layout (the generator's evaluation sets use it).
#include <filesystem>
#include <iomanip>
#include <ostream>

#include "data/colmap.h"
#include "io/atomic_file.h"

namespace isplat {
namespace fs = std::filesystem;

namespace {

template <class T>
void colmap_put(std::ostream& os, T v) {
  os.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

std::string colmap_out_path(const std::string& dir, const std::string& name) {
  return (fs::path(dir) / name).string();
}

}  // namespace

void write_colmap_text(const std::string& dir, const ColmapModel& m) {
  write_file_atomic(colmap_out_path(dir, "cameras.txt"), [&](std::ostream& os) {
    os << std::setprecision(17);
    os << "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n";
    os << "# Number of cameras: " << m.cameras.size() << "\n";
    for (const auto& [id, c] : m.cameras) {
      os << id << " " << colmap_model_by_id(c.model_id)->name << " " << c.width << " " << c.height;
      for (double p : c.params) os << " " << p;
      os << "\n";
    }
  });
  write_file_atomic(colmap_out_path(dir, "images.txt"), [&](std::ostream& os) {
    os << std::setprecision(17);
    os << "# Image list with two lines of data per image:\n"
          "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
          "#   POINTS2D[] as (X, Y, POINT3D_ID)\n";
    os << "# Number of images: " << m.images.size() << "\n";
    for (const auto& [id, img] : m.images) {
      os << id;
      for (int k = 0; k < 4; ++k) os << " " << img.qvec[k];
      for (int k = 0; k < 3; ++k) os << " " << img.tvec[k];
      os << " " << img.camera_id << " " << img.name << "\n";
      for (size_t k = 0; k < img.xys.size(); ++k)
        os << (k ? " " : "") << img.xys[k].x() << " " << img.xys[k].y() << " " << img.point3D_ids[k];
      os << "\n";
    }
  });
  write_file_atomic(colmap_out_path(dir, "points3D.txt"), [&](std::ostream& os) {
    os << std::setprecision(17);
    os << "# 3D point list with one line of data per point:\n"
          "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n";
    os << "# Number of points: " << m.points.size() << "\n";
    for (const auto& [id, p] : m.points) {
      os << id << " " << p.xyz.x() << " " << p.xyz.y() << " " << p.xyz.z() << " " << int(p.rgb[0]) << " "
         << int(p.rgb[1]) << " " << int(p.rgb[2]) << " " << p.error;
      for (const auto& t : p.track) os << " " << t.first << " " << t.second;
      os << "\n";
    }
  });
}

void write_colmap_binary(const std::string& dir, const ColmapModel& m) {
  write_file_atomic(colmap_out_path(dir, "cameras.bin"), [&](std::ostream& os) {
    colmap_put<uint64_t>(os, m.cameras.size());
    for (const auto& [id, c] : m.cameras) {
      colmap_put<uint32_t>(os, static_cast<uint32_t>(id));
      colmap_put<int32_t>(os, c.model_id);
      colmap_put<uint64_t>(os, static_cast<uint64_t>(c.width));
      colmap_put<uint64_t>(os, static_cast<uint64_t>(c.height));
      for (double p : c.params) colmap_put<double>(os, p);
    }
  });
  write_file_atomic(colmap_out_path(dir, "images.bin"), [&](std::ostream& os) {
    colmap_put<uint64_t>(os, m.images.size());
    for (const auto& [id, img] : m.images) {
      colmap_put<uint32_t>(os, static_cast<uint32_t>(id));
      for (int k = 0; k < 4; ++k) colmap_put<double>(os, img.qvec[k]);
      for (int k = 0; k < 3; ++k) colmap_put<double>(os, img.tvec[k]);
      colmap_put<uint32_t>(os, static_cast<uint32_t>(img.camera_id));
      os.write(img.name.c_str(), static_cast<std::streamsize>(img.name.size() + 1));
      colmap_put<uint64_t>(os, img.xys.size());
      for (size_t k = 0; k < img.xys.size(); ++k) {
        colmap_put<double>(os, img.xys[k].x());
        colmap_put<double>(os, img.xys[k].y());
        colmap_put<int64_t>(os, img.point3D_ids[k]);
      }
    }
  });
  write_file_atomic(colmap_out_path(dir, "points3D.bin"), [&](std::ostream& os) {
    colmap_put<uint64_t>(os, m.points.size());
    for (const auto& [id, p] : m.points) {
      colmap_put<uint64_t>(os, static_cast<uint64_t>(id));
      for (int k = 0; k < 3; ++k) colmap_put<double>(os, p.xyz[k]);
      for (int k = 0; k < 3; ++k) colmap_put<uint8_t>(os, p.rgb[k]);
      colmap_put<double>(os, p.error);
      colmap_put<uint64_t>(os, p.track.size());
      for (const auto& t : p.track) {
        colmap_put<uint32_t>(os, static_cast<uint32_t>(t.first));
        colmap_put<uint32_t>(os, static_cast<uint32_t>(t.second));
      }
    }
  });
}

}  // namespace isplat
