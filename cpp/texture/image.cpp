// Texture "image": an image file read through OpenImageIO (io/image_io.cpp),
// bilinearly filtered, with repeat / clamp / mirror wrapping.
#include <cmath>

#include "core/error.h"
#include "io/image_io.h"
#include "texture/texture.h"
#include "texture/texture_registry.h"

namespace sg {

enum class Wrap { Repeat, Clamp, Mirror };

class ImageTexture final : public Texture {
 public:
  ImageTexture(ImageData img, Wrap wrap, const Color& scale) : m_img(std::move(img)), m_wrap(wrap), m_scale(scale) {
    double acc[3] = {0, 0, 0};
    size_t n = size_t(m_img.width) * m_img.height;
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) acc[c] += texel_channel(i, c);
    m_average = Color(float(acc[0] / n), float(acc[1] / n), float(acc[2] / n)) * m_scale;
  }

  Color eval(const Vec2f& uv, float /*footprint*/) const override {
    // NOTE: texture space has v pointing up (glTF/OBJ convention); image rows go down.
    float x = uv.x * m_img.width - 0.5f;
    float y = (1.f - uv.y) * m_img.height - 0.5f;
    float fx = std::floor(x), fy = std::floor(y);
    float tx = x - fx, ty = y - fy;
    int x0 = int(fx), y0 = int(fy);
    Color c00 = texel(x0, y0), c10 = texel(x0 + 1, y0), c01 = texel(x0, y0 + 1), c11 = texel(x0 + 1, y0 + 1);
    Color c = (c00 * (1 - tx) + c10 * tx) * (1 - ty) + (c01 * (1 - tx) + c11 * tx) * ty;
    return c * m_scale;
  }
  Color average() const override { return m_average; }

 private:
  int wrap_coord(int i, int n) const {
    switch (m_wrap) {
      case Wrap::Clamp: return std::min(std::max(i, 0), n - 1);
      case Wrap::Mirror: {
        int period = 2 * n;
        int m = ((i % period) + period) % period;
        return m < n ? m : period - 1 - m;
      }
      default: return ((i % n) + n) % n;
    }
  }
  float texel_channel(size_t pixel, int c) const {
    int ch = m_img.channels >= 3 ? c : 0;
    return m_img.pixels[pixel * m_img.channels + ch];
  }
  Color texel(int x, int y) const {
    size_t i = size_t(wrap_coord(y, m_img.height)) * m_img.width + wrap_coord(x, m_img.width);
    return Color(texel_channel(i, 0), texel_channel(i, 1), texel_channel(i, 2));
  }

  ImageData m_img;
  Wrap m_wrap;
  Color m_scale, m_average;
};

std::shared_ptr<Texture> make_image_texture(const ImageData& pixels, const Color& scale) {
  return std::make_shared<ImageTexture>(pixels, Wrap::Repeat, scale);
}

std::shared_ptr<Texture> create_image_texture(const ParamSet& params) {
  std::string filename = params.get_string("filename", "");
  if (filename.empty()) throw Error("image texture: parameter 'filename' is required");
  std::string cs = params.get_string("colorspace", "auto");
  std::string wrap_s = params.get_string("wrap", "repeat");
  Color scale = params.get_color("scale", Color(1.f));
  Wrap wrap;
  if (wrap_s == "repeat") wrap = Wrap::Repeat;
  else if (wrap_s == "clamp") wrap = Wrap::Clamp;
  else if (wrap_s == "mirror") wrap = Wrap::Mirror;
  else throw Error("image texture: 'wrap' must be repeat, clamp or mirror, got '" + wrap_s + "'");
  ColorSpace space;
  if (cs == "auto") space = ColorSpace::Auto;
  else if (cs == "srgb") space = ColorSpace::SRGB;
  else if (cs == "linear") space = ColorSpace::Linear;
  else throw Error("image texture: 'colorspace' must be auto, srgb or linear, got '" + cs + "'");
  return std::make_shared<ImageTexture>(load_image(filename, space), wrap, scale);
}

}  // namespace sg
