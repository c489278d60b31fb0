// pectus: Image, PNG, text and stacking on OpenCV.
#include "shape/render/image.h"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"

namespace pectus::render {
namespace {

// A cv::Mat header over the image's bytes (RGB order; OpenCV only draws, so the order does not matter
// except on encoding, where it is swapped).
cv::Mat View(Image* image) { return cv::Mat(image->height, image->width, CV_8UC3, image->rgb.data()); }
cv::Scalar Colour(Rgb c) { return cv::Scalar(c.r, c.g, c.b); }

}  // namespace

Image::Image(int w, int h, Rgb fill) : width(std::max(0, w)), height(std::max(0, h)) {
  rgb.resize(static_cast<std::size_t>(width) * height * 3);
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    rgb[i] = fill.r;
    rgb[i + 1] = fill.g;
    rgb[i + 2] = fill.b;
  }
}

Rgb Image::at(int x, int y) const {
  const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 3;
  return {rgb[i], rgb[i + 1], rgb[i + 2]};
}

void Image::Set(int x, int y, Rgb c) {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 3;
  rgb[i] = c.r;
  rgb[i + 1] = c.g;
  rgb[i + 2] = c.b;
}

void DrawText(Image* image, int x, int y, const std::string& text, double scale, Rgb colour, int thickness) {
  if (image->empty()) return;
  cv::Mat m = View(image);
  cv::putText(m, text, cv::Point(x, y), cv::FONT_HERSHEY_SIMPLEX, scale, Colour(colour), thickness, cv::LINE_AA);
}

void TextSize(const std::string& text, double scale, int thickness, int* width, int* height) {
  int baseline = 0;
  const cv::Size s = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
  *width = s.width;
  *height = s.height + baseline;
}

void DrawLine(Image* image, int x0, int y0, int x1, int y1, Rgb colour, int thickness) {
  if (image->empty()) return;
  cv::Mat m = View(image);
  cv::line(m, cv::Point(x0, y0), cv::Point(x1, y1), Colour(colour), thickness, cv::LINE_AA);
}

void FillRect(Image* image, int x0, int y0, int x1, int y1, Rgb colour) {
  if (image->empty()) return;
  cv::Mat m = View(image);
  cv::rectangle(m, cv::Point(std::min(x0, x1), std::min(y0, y1)), cv::Point(std::max(x0, x1), std::max(y0, y1)),
                Colour(colour), cv::FILLED);
}

namespace {

void Blit(const Image& src, int x0, int y0, Image* dst) {
  for (int y = 0; y < src.height; ++y) {
    if (y + y0 < 0 || y + y0 >= dst->height) continue;
    const int w = std::min(src.width, dst->width - x0);
    if (w <= 0) continue;
    std::copy_n(src.rgb.data() + static_cast<std::size_t>(y) * src.width * 3, static_cast<std::size_t>(w) * 3,
                dst->rgb.data() + (static_cast<std::size_t>(y + y0) * dst->width + x0) * 3);
  }
}

}  // namespace

Image HStack(const std::vector<Image>& images, int gap, Rgb fill) {
  int w = 0, h = 0;
  for (const Image& im : images) {
    w += im.width;
    h = std::max(h, im.height);
  }
  if (!images.empty()) w += gap * static_cast<int>(images.size() - 1);
  Image out(w, h, fill);
  int x = 0;
  for (const Image& im : images) {
    Blit(im, x, 0, &out);
    x += im.width + gap;
  }
  return out;
}

Image VStack(const std::vector<Image>& images, int gap, Rgb fill) {
  int w = 0, h = 0;
  for (const Image& im : images) {
    h += im.height;
    w = std::max(w, im.width);
  }
  if (!images.empty()) h += gap * static_cast<int>(images.size() - 1);
  Image out(w, h, fill);
  int y = 0;
  for (const Image& im : images) {
    Blit(im, 0, y, &out);
    y += im.height + gap;
  }
  return out;
}

Image WithTitle(const Image& image, const std::string& title, int height, double scale) {
  Image band(image.width, height, kWhite);
  int tw = 0, th = 0;
  TextSize(title, scale, 1, &tw, &th);
  DrawText(&band, std::max(2, (image.width - tw) / 2), (height + th) / 2 - 2, title, scale, kBlack, 1);
  return VStack({band, image});
}

std::string EncodePng(const Image& image) {
  if (image.empty()) ThrowFailure("cannot encode an empty image as PNG");
  cv::Mat rgb(image.height, image.width, CV_8UC3, const_cast<std::uint8_t*>(image.rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  std::vector<std::uint8_t> bytes;
  if (!cv::imencode(".png", bgr, bytes)) ThrowFailure("PNG encoding failed");
  return std::string(bytes.begin(), bytes.end());
}

void WritePng(const Image& image, const std::filesystem::path& path) {
  WriteFileAtomically(path, EncodePng(image));
}

Image ReadImage(const std::filesystem::path& path) {
  const cv::Mat bgr = cv::imread(path.string(), cv::IMREAD_COLOR);
  if (bgr.empty()) ThrowBadInput(path.string(), "not a readable image");
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  Image out(rgb.cols, rgb.rows);
  for (int y = 0; y < rgb.rows; ++y) std::copy_n(rgb.ptr<std::uint8_t>(y), rgb.cols * 3, out.rgb.data() + y * rgb.cols * 3);
  return out;
}

}  // namespace pectus::render
