// The EXIF focal length of a JPEG (35 mm equivalent), for intrinsics when a photo comes without them.
#pragma once
#include <optional>
#include <string>

namespace isplat {

struct ExifFocal {
  std::optional<double> focal_35mm;  // FocalLengthIn35mmFilm (0xA405), millimetres
  std::optional<double> focal_mm;    // FocalLength (0x920A), millimetres (sensor size unknown)
};

// Parses the APP1 Exif segment of JPEG bytes. Missing or malformed EXIF gives empty fields, never an error.
ExifFocal read_exif_focal(const std::string& jpeg_bytes);

// fx in pixels from a 35 mm-equivalent focal length: the longer image side spans 36 mm.
double fx_from_35mm(double focal_35mm, int width, int height);

}  // namespace isplat
