// An RGBA8 image as OSMesa renders it, with 2D drawing for the overlays (text, filled
// rectangles) and PNG output. Public header of the render module.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace render {

struct Rgba8 {
  uint8_t r = 0, g = 0, b = 0, a = 255;
  bool operator==(const Rgba8& o) const { return r == o.r && g == o.g && b == o.b && a == o.a; }
  bool operator!=(const Rgba8& o) const { return !(*this == o); }
};

class Image {
 public:
  void Resize(int width, int height);
  int width() const { return width_; }
  int height() const { return height_; }
  // Pixel (x, y), y counted from the top row of the picture (0 = top).
  Rgba8 At(int x, int y) const;
  void Set(int x, int y, Rgba8 c);                     // ignores pixels outside the image
  void FillRect(int x, int y, int w, int h, Rgba8 c);  // clipped to the image
  // The same, blended over what is there by c.a / 255 (a text's backing plate).
  void BlendRect(int x, int y, int w, int h, Rgba8 c);
  // Storage: rows bottom-up (OpenGL order), 4 bytes a pixel, no padding (width * height * 4).
  uint8_t* data() { return pixels_.data(); }
  const uint8_t* data() const { return pixels_.data(); }
  const uint8_t* RowFromTop(int y) const {
    return pixels_.data() + static_cast<size_t>(height_ - 1 - y) * width_ * 4;
  }

 private:
  int width_ = 0, height_ = 0;
  std::vector<uint8_t> pixels_;
};

// Built-in 5x9 bitmap font (printable ASCII subset; others draw as '?'), each glyph cell
// 6 x 10 pixels times `scale`. (x, y) is the top-left corner, y from the top.
constexpr int kGlyphAdvance = 6;
constexpr int kGlyphHeight = 10;
int TextWidth(const std::string& text, int scale);
void DrawText(Image* image, int x, int y, const std::string& text, int scale, Rgba8 color);

// Writes `image` as an 8-bit RGB PNG (alpha dropped). `level` is the zlib level 0..9
// (1: fastest that still compresses, see docs/render.md). Throws std::runtime_error naming the
// path when the file cannot be written.
void WritePng(const std::string& path, const Image& image, int level = 1);

}  // namespace render
