// pectus: an RGB image in memory, PNG output, text and stacking. OpenCV stays behind this header.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace pectus::render {

/// An 8-bit colour.
struct Rgb {
  std::uint8_t r = 0, g = 0, b = 0;
};

inline constexpr Rgb kWhite{255, 255, 255};
inline constexpr Rgb kBlack{0, 0, 0};
inline constexpr Rgb kGrey{160, 160, 160};

/// A width by height RGB image, row-major, 3 bytes a pixel, (0, 0) at the top left.
struct Image {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< width * height * 3 bytes

  Image() = default;
  /// A width by height image filled with `fill`.
  Image(int width, int height, Rgb fill = kWhite);
  bool empty() const { return width <= 0 || height <= 0; }
  Rgb at(int x, int y) const;
  /// Sets one pixel; coordinates outside the image are ignored.
  void Set(int x, int y, Rgb colour);
};

/// Text at (x, y) (the baseline's left end), Hershey simplex font; `scale` 1 is about 20 px tall.
void DrawText(Image* image, int x, int y, const std::string& text, double scale = 0.6, Rgb colour = kBlack,
              int thickness = 1);
/// Width and height in pixels of `text` as DrawText would draw it.
void TextSize(const std::string& text, double scale, int thickness, int* width, int* height);
/// A straight line from (x0, y0) to (x1, y1), anti-aliased.
void DrawLine(Image* image, int x0, int y0, int x1, int y1, Rgb colour, int thickness = 1);
/// A filled axis-aligned rectangle with corners (x0, y0) and (x1, y1), inclusive.
void FillRect(Image* image, int x0, int y0, int x1, int y1, Rgb colour);

/// Images side by side (heights padded with `fill` to the tallest).
Image HStack(const std::vector<Image>& images, int gap = 0, Rgb fill = kWhite);
/// Images one above the other (widths padded with `fill` to the widest).
Image VStack(const std::vector<Image>& images, int gap = 0, Rgb fill = kWhite);
/// A copy with a `height` pixel band on top holding `title`, centred.
Image WithTitle(const Image& image, const std::string& title, int height = 32, double scale = 0.7);

/// The image encoded as PNG bytes.
std::string EncodePng(const Image& image);
/// Writes the image as a PNG file, atomically (throws pectus::Error naming the file on failure).
void WritePng(const Image& image, const std::filesystem::path& path);
/// Reads a PNG back as 8-bit RGB; throws pectus::Error(kBadInput) naming the file.
Image ReadImage(const std::filesystem::path& path);

}  // namespace pectus::render
