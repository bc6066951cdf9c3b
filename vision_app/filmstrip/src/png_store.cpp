// Stored (uncompressed, unfiltered) PNG through libpng.
#include "png_store.hpp"

#include <png.h>
#include <zlib.h>

#include <csetjmp>

namespace picksight::filmstrip {
namespace {
void append(png_structp png, png_bytep data, png_size_t n) {
  auto* out = static_cast<std::string*>(png_get_io_ptr(png));
  out->append(reinterpret_cast<const char*>(data), n);
}
void noFlush(png_structp) {}

// libpng's write and info structs, destroyed together.
struct PngWriter {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  ~PngWriter() { png_destroy_write_struct(&png, &info); }
};
}  // namespace

std::optional<std::string> storedPng(const cv::Mat& image) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 1 && image.channels() != 3))
    return std::nullopt;
  std::string out;
  out.reserve(image.total() * image.elemSize() + image.rows * 8 + 4096);
  PngWriter w;
  if (!w.png || !w.info) return std::nullopt;
  // libpng reports its errors by longjmp: nothing with a destructor is
  // made between here and the end.
  if (setjmp(png_jmpbuf(w.png))) return std::nullopt;
  png_set_write_fn(w.png, &out, append, noFlush);
  png_set_IHDR(w.png, w.info, static_cast<png_uint_32>(image.cols),
               static_cast<png_uint_32>(image.rows), 8,
               image.channels() == 1 ? PNG_COLOR_TYPE_GRAY : PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_filter(w.png, 0, PNG_FILTER_NONE);
  png_set_compression_level(w.png, Z_NO_COMPRESSION);
  png_write_info(w.png, w.info);
  if (image.channels() == 3) png_set_bgr(w.png);
  for (int y = 0; y < image.rows; ++y)
    png_write_row(w.png, const_cast<png_bytep>(image.ptr<uchar>(y)));
  png_write_end(w.png, w.info);
  return out;
}

}  // namespace picksight::filmstrip
