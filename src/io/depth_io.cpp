// OpenEXR depth reading/writing and depth sanitization.
#include "io/depth_io.h"

#include <ImathBox.h>
#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfOutputFile.h>

#include <cmath>
#include <filesystem>
#include <vector>

#include "core/error.h"
#include "io/atomic_file.h"

namespace isplat {

DepthMap sanitize_depth(const cv::Mat& raw) {
  ISPLAT_CHECK(raw.channels() == 1, "depth map must have one channel, got ", raw.channels());
  DepthMap out;
  raw.convertTo(out.depth, CV_32F);
  out.valid = cv::Mat::zeros(raw.rows, raw.cols, CV_8UC1);
  for (int i = 0; i < out.depth.rows; ++i) {
    float* d = out.depth.ptr<float>(i);
    uint8_t* v = out.valid.ptr<uint8_t>(i);
    for (int j = 0; j < out.depth.cols; ++j) {
      if (std::isfinite(d[j]) && d[j] > 0.0f) {
        v[j] = 1;
      } else {
        d[j] = 0.0f;
        ++out.invalid_count;
      }
    }
  }
  return out;
}

cv::Mat read_exr_channel(const std::string& path, const std::string& channel) {
  if (!std::filesystem::exists(path)) fail(path, ": no such file");
  try {
    Imf::InputFile file(path.c_str());
    const Imf::ChannelList& channels = file.header().channels();
    std::string name = channel;
    if (name.empty()) {
      for (const char* c : {"Z", "Y", "R", "depth", "D"})
        if (channels.findChannel(c)) {
          name = c;
          break;
        }
      if (name.empty()) {
        int count = 0;
        for (auto it = channels.begin(); it != channels.end(); ++it, ++count) name = it.name();
        if (count != 1) fail(path, ": no Z/Y/R channel and ", count, " channels; pass the channel name");
      }
    } else if (!channels.findChannel(name.c_str())) {
      std::string names;
      for (auto it = channels.begin(); it != channels.end(); ++it)
        names += std::string(names.empty() ? "" : ", ") + it.name();
      fail(path, ": no channel '", name, "' (channels: ", names, ")");
    }
    if (!file.isComplete()) fail(path, ": truncated EXR (pixel data incomplete)");
    const Imath::Box2i dw = file.header().dataWindow();
    const int width = dw.max.x - dw.min.x + 1, height = dw.max.y - dw.min.y + 1;
    if (width <= 0 || height <= 0) fail(path, ": empty data window");
    cv::Mat out(height, width, CV_32FC1);
    Imf::FrameBuffer fb;
    char* base = reinterpret_cast<char*>(out.ptr<float>(0)) -
                 (static_cast<ptrdiff_t>(dw.min.x) + static_cast<ptrdiff_t>(dw.min.y) * width) * sizeof(float);
    fb.insert(name.c_str(), Imf::Slice(Imf::FLOAT, base, sizeof(float), sizeof(float) * width));
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);
    return out;
  } catch (const Error&) {
    throw;
  } catch (const std::exception& e) {
    fail(path, ": cannot read EXR: ", e.what());
  }
}

DepthMap read_depth_exr(const std::string& path, const std::string& channel) {
  return sanitize_depth(read_exr_channel(path, channel));
}

void write_depth_exr(const std::string& path, const cv::Mat& depth, bool half) {
  ISPLAT_CHECK(depth.type() == CV_32FC1 && !depth.empty(), path, ": write_depth_exr expects a non-empty CV_32FC1 map");
  cv::Mat contiguous = depth.isContinuous() ? depth : depth.clone();
  AtomicPath target(path);
  try {
    Imf::Header header(contiguous.cols, contiguous.rows);
    header.channels().insert("Z", Imf::Channel(half ? Imf::HALF : Imf::FLOAT));
    Imf::OutputFile file(target.temp().c_str(), header);
    Imf::FrameBuffer fb;
    fb.insert("Z", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(contiguous.ptr<float>(0)), sizeof(float),
                              sizeof(float) * contiguous.cols));
    file.setFrameBuffer(fb);
    file.writePixels(contiguous.rows);
  } catch (const std::exception& e) {
    fail(path, ": cannot write EXR: ", e.what());
  }
  target.commit();
}

}  // namespace isplat
