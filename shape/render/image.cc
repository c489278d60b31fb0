// pectus: Image, text and stacking on OpenCV's drawing; PNG through libpng's simplified API (OpenCV's
// image codecs would bring 140 shared libraries, GDAL, DICOM and video codecs among them, into every
// process that may write a picture: most of `pectus`'s start-up).
#include "shape/render/image.h"

#include <png.h>

#include <algorithm>
#include <memory>
#include <opencv2/imgproc.hpp>

#include "shape/core/atomic_file.h"
#include "shape/core/error.h"

namespace pectus::render {
namespace {

// A cv::Mat header over the image's bytes (RGB order; OpenCV only draws, so the order does not matter
// except on encoding, where it is swapped).
cv::Mat MatOver(Image* image) { return cv::Mat(image->height, image->width, CV_8UC3, image->rgb.data()); }
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
  cv::Mat m = MatOver(image);
  cv::putText(m, text, cv::Point(x, y), cv::FONT_HERSHEY_SIMPLEX, scale, Colour(colour), thickness,
              cv::LINE_AA);
}

void TextSize(const std::string& text, double scale, int thickness, int* width, int* height) {
  int baseline = 0;
  const cv::Size s = cv::getTextSize(text, cv::FONT_HERSHEY_SIMPLEX, scale, thickness, &baseline);
  *width = s.width;
  *height = s.height + baseline;
}

void DrawLine(Image* image, int x0, int y0, int x1, int y1, Rgb colour, int thickness) {
  if (image->empty()) return;
  cv::Mat m = MatOver(image);
  cv::line(m, cv::Point(x0, y0), cv::Point(x1, y1), Colour(colour), thickness, cv::LINE_AA);
}

void FillRect(Image* image, int x0, int y0, int x1, int y1, Rgb colour) {
  if (image->empty()) return;
  cv::Mat m = MatOver(image);
  cv::rectangle(m, cv::Point(std::min(x0, x1), std::min(y0, y1)),
                cv::Point(std::max(x0, x1), std::max(y0, y1)), Colour(colour), cv::FILLED);
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
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width);
  png.height = static_cast<png_uint_32>(image.height);
  png.format = PNG_FORMAT_RGB;
  const png_int_32 stride = image.width * 3;
  png_alloc_size_t size = 0;  // first call: the size the encoding needs
  if (!png_image_write_to_memory(&png, nullptr, &size, 0, image.rgb.data(), stride, nullptr)) {
    ThrowFailure(std::string("PNG encoding failed: ") + png.message);
  }
  std::string bytes(size, '\0');
  if (!png_image_write_to_memory(&png, bytes.data(), &size, 0, image.rgb.data(), stride, nullptr)) {
    ThrowFailure(std::string("PNG encoding failed: ") + png.message);
  }
  bytes.resize(size);
  return bytes;
}

void WritePng(const Image& image, const std::filesystem::path& path) {
  WriteFileAtomically(path, EncodePng(image));
}

Image ReadImage(const std::filesystem::path& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str())) {
    ThrowBadInput(path.string(), std::string("not a readable PNG image (") + png.message + ")");
  }
  // Frees libpng's reading state on every way out, as png_image_finish_read does on success.
  const std::unique_ptr<png_image, void (*)(png_image*)> guard(&png, png_image_free);
  png.format = PNG_FORMAT_RGB;  // grey, palette and alpha images are converted to 8-bit RGB
  if (png.width == 0 || png.height == 0 || png.width > 1u << 15 || png.height > 1u << 15) {
    ThrowBadInput(path.string(), "PNG image of " + std::to_string(png.width) + " x " +
                                     std::to_string(png.height) + " pixels (1 to 32768 a side)");
  }
  Image out(static_cast<int>(png.width), static_cast<int>(png.height));
  if (!png_image_finish_read(&png, nullptr, out.rgb.data(), out.width * 3, nullptr)) {
    ThrowBadInput(path.string(), std::string("corrupt PNG image (") + png.message + ")");
  }
  return out;
}

}  // namespace pectus::render
