// The codecs module: the only code of PickSight linked with OpenCV's
// imgcodecs and videoio (see codecs.hpp for why).
#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "module_table.hpp"

namespace {

cv::Mat readImage(const std::string& path, int flags) { return cv::imread(path, flags); }

bool writeImage(const std::string& path, cv::InputArray image, const std::vector<int>& params) {
  return cv::imwrite(path, image, params);
}

cv::Mat decodeImage(cv::InputArray bytes, int flags) { return cv::imdecode(bytes, flags); }

bool encodeImage(const std::string& ext, cv::InputArray image, std::vector<uchar>& bytes,
                 const std::vector<int>& params) {
  return cv::imencode(ext, image, bytes, params);
}

bool haveWriter(const std::string& path) { return cv::haveImageWriter(path); }

class CaptureStream final : public picksight::codecs::VideoStream {
 public:
  bool open(const std::string& url, int api, const std::vector<int>& params) override {
    return capture_.open(url, api, params);
  }
  bool isOpened() const override { return capture_.isOpened(); }
  bool grab() override { return capture_.grab(); }
  bool retrieve(cv::Mat& image) override { return capture_.retrieve(image); }
  double get(int property) const override { return capture_.get(property); }
  bool set(int property, double value) override { return capture_.set(property, value); }

 private:
  cv::VideoCapture capture_;
};

picksight::codecs::VideoStream* newStream() { return new CaptureStream(); }

const picksight::codecs::ModuleTable kTable{picksight::codecs::kModuleVersion,
                                            readImage,
                                            writeImage,
                                            decodeImage,
                                            encodeImage,
                                            haveWriter,
                                            newStream};

}  // namespace

extern "C" __attribute__((visibility("default"))) const picksight::codecs::ModuleTable*
picksight_codecs_table() {
  return &kTable;
}
