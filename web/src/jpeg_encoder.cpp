// libjpeg-turbo behind a small RAII class.
#include "picksight/web/jpeg_encoder.hpp"

#include <turbojpeg.h>

#include <stdexcept>

namespace picksight::web {

JpegEncoder::JpegEncoder(int quality) : handle_(tjInitCompress()), quality_(quality) {
  if (!handle_) throw std::runtime_error("turbojpeg: cannot create a compressor");
}

JpegEncoder::~JpegEncoder() { tjDestroy(static_cast<tjhandle>(handle_)); }

Result<std::string> JpegEncoder::encode(const cv::Mat& image) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    return makeError(WebErrc::kEncode, "only 8-bit mono or BGR images are encoded");
  const bool mono = image.channels() == 1;
  unsigned char* out = nullptr;  // allocated by turbojpeg, freed below
  unsigned long size = 0;
  const int rc =
      tjCompress2(static_cast<tjhandle>(handle_), image.data, image.cols,
                  static_cast<int>(image.step[0]), image.rows, mono ? TJPF_GRAY : TJPF_BGR, &out,
                  &size, mono ? TJSAMP_GRAY : TJSAMP_420, quality_, TJFLAG_FASTDCT);
  if (rc != 0) {
    const std::string why = tjGetErrorStr2(static_cast<tjhandle>(handle_));
    tjFree(out);
    return makeError(WebErrc::kEncode, "JPEG encoding failed: " + why);
  }
  std::string bytes(reinterpret_cast<const char*>(out), size);
  tjFree(out);
  return bytes;
}

}  // namespace picksight::web
