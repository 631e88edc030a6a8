#include "prtlab/btf/utia_btf.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <utility>
#include <vector>

#include "prtlab/base/error.h"
#include "prtlab/image/image_io.h"
#include "prtlab/sphere/hemisphere_grid.h"
#include "prtlab/storage/atomic_file.h"

// stb_image reads 8- and 16-bit PNGs; image_io only writes tone-mapped 8-bit ones. The zlib
// encoder of stb_image_write is reused for 16-bit PNGs, which stb_image_write cannot write.
#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#define STBI_ONLY_PNG
#define STBI_NO_STDIO
#include <stb/stb_image.h>
#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STBI_WRITE_NO_STDIO
#include <stb/stb_image_write.h>

namespace prt {
namespace fs = std::filesystem;

namespace {

constexpr double kDeg = kPi / 180.0;
constexpr double kMinNamedCosine = 1e-3;

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// Digits with an optional fraction; advances `s` past them.
std::optional<double> parse_angle(std::string_view& s) {
  std::size_t n = 0;
  while (n < s.size() && std::isdigit(static_cast<unsigned char>(s[n]))) ++n;
  if (n == 0) return std::nullopt;
  // A '.' starts a fraction only when a digit follows: the one of ".png" ends the angle.
  if (n + 1 < s.size() && s[n] == '.' && std::isdigit(static_cast<unsigned char>(s[n + 1]))) {
    ++n;
    while (n < s.size() && std::isdigit(static_cast<unsigned char>(s[n]))) ++n;
  }
  double value = 0;
  const auto r = std::from_chars(s.data(), s.data() + n, value);
  if (r.ec != std::errc() || r.ptr != s.data() + n) return std::nullopt;
  s.remove_prefix(n);
  return value;
}

bool consume(std::string_view& s, std::string_view prefix) {
  if (s.substr(0, prefix.size()) != prefix) return false;
  s.remove_prefix(prefix.size());
  return true;
}

bool is_image_extension(const std::string& ext) {
  return ext == ".png" || ext == ".exr";
}

std::vector<unsigned char> read_file_bytes(const fs::path& file) {
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  if (ec) throw InputError(file, fmt::format("cannot read: {}", ec.message()));
  if (size > (std::uintmax_t{1} << 31) - 1) throw InputError(file, "PNG larger than 2 GiB");
  std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
  std::ifstream in(file, std::ios::binary);
  if (!in) throw InputError(file, "cannot open for reading");
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  if (!in) throw InputError(file, "read failed");
  return bytes;
}

// Linear PNG samples: value / 255 or / 65535, grey expanded to RGB, alpha dropped.
RgbImage read_png_linear(const fs::path& file) {
  const std::vector<unsigned char> bytes = read_file_bytes(file);
  const int len = static_cast<int>(bytes.size());
  // The size a PNG declares is read from its IHDR before stb sees it: stb refuses a huge one
  // but then tries its other formats and reports "unknown image type".
  constexpr long long kMaxPixels = 1LL << 28;
  static constexpr unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  if (bytes.size() >= 24 && std::equal(kSignature, kSignature + 8, bytes.begin()) &&
      std::equal(bytes.begin() + 12, bytes.begin() + 16, "IHDR")) {
    const auto be32 = [&](std::size_t at) {
      return static_cast<std::uint32_t>(bytes[at]) << 24 |
             static_cast<std::uint32_t>(bytes[at + 1]) << 16 |
             static_cast<std::uint32_t>(bytes[at + 2]) << 8 |
             static_cast<std::uint32_t>(bytes[at + 3]);
    };
    const std::uint64_t dw = be32(16), dh = be32(20);
    if (dw == 0 || dh == 0)
      throw InputError(file, fmt::format("the PNG declares {} x {} pixels", dw, dh));
    if (dw > (1u << 24) || dh > (1u << 24) || dw * dh > static_cast<std::uint64_t>(kMaxPixels))
      throw InputError(file, fmt::format("the PNG declares {} x {} pixels: too large (at most {} "
                                         "pixels, {} per side)",
                                         dw, dh, kMaxPixels, 1u << 24));
  }
  int w = 0, h = 0, n = 0;
  if (!stbi_info_from_memory(bytes.data(), len, &w, &h, &n))
    throw InputError(file, fmt::format("cannot read as PNG: {}", stbi_failure_reason()));
  if (w <= 0 || h <= 0 || static_cast<long long>(w) * h > kMaxPixels)
    throw InputError(file, fmt::format("unsupported PNG size {} x {}", w, h));
  RgbImage image(w, h);
  if (stbi_is_16_bit_from_memory(bytes.data(), len)) {
    stbi_us* p = stbi_load_16_from_memory(bytes.data(), len, &w, &h, &n, 3);
    if (!p) throw InputError(file, fmt::format("cannot decode PNG: {}", stbi_failure_reason()));
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
      image.pixels[i] = Rgb(p[3 * i], p[3 * i + 1], p[3 * i + 2]) / 65535.0f;
    stbi_image_free(p);
  } else {
    stbi_uc* p = stbi_load_from_memory(bytes.data(), len, &w, &h, &n, 3);
    if (!p) throw InputError(file, fmt::format("cannot decode PNG: {}", stbi_failure_reason()));
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
      image.pixels[i] = Rgb(p[3 * i], p[3 * i + 1], p[3 * i + 2]) / 255.0f;
    stbi_image_free(p);
  }
  return image;
}

RgbImage read_tile_image(const fs::path& file) {
  return lower(file.extension().string()) == ".exr" ? read_exr(file) : read_png_linear(file);
}

std::uint32_t crc32(const unsigned char* data, std::size_t n, std::uint32_t crc = 0) {
  static const std::array<std::uint32_t, 256> table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xEDB88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
  return ~crc;
}

void put_be32(std::vector<unsigned char>& out, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<unsigned char>(v >> s));
}

void put_chunk(std::vector<unsigned char>& out, const char type[4],
               const std::vector<unsigned char>& data) {
  put_be32(out, static_cast<std::uint32_t>(data.size()));
  const std::size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), data.begin(), data.end());
  put_be32(out, crc32(out.data() + start, out.size() - start));
}

// A 16-bit RGB PNG, unfiltered rows (filter byte 0) compressed by stb's zlib encoder.
std::vector<unsigned char> encode_png16(int width, int height,
                                        const std::vector<std::uint16_t>& rgb) {
  std::vector<unsigned char> raw;
  raw.reserve(static_cast<std::size_t>(height) * (1 + static_cast<std::size_t>(width) * 6));
  for (int y = 0; y < height; ++y) {
    raw.push_back(0);
    for (int x = 0; x < width * 3; ++x) {
      const std::uint16_t v = rgb[static_cast<std::size_t>(y) * width * 3 + x];
      raw.push_back(static_cast<unsigned char>(v >> 8));
      raw.push_back(static_cast<unsigned char>(v & 0xFF));
    }
  }
  int zlen = 0;
  unsigned char* z = stbi_zlib_compress(raw.data(), static_cast<int>(raw.size()), &zlen, 8);
  PRT_CHECK(z != nullptr, "zlib compression failed");
  std::vector<unsigned char> idat(z, z + zlen);
  STBIW_FREE(z);
  std::vector<unsigned char> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
  std::vector<unsigned char> ihdr;
  put_be32(ihdr, static_cast<std::uint32_t>(width));
  put_be32(ihdr, static_cast<std::uint32_t>(height));
  ihdr.insert(ihdr.end(), {16, 2, 0, 0, 0});  // 16 bit, RGB, deflate, no filter set, no interlace
  put_chunk(png, "IHDR", ihdr);
  put_chunk(png, "IDAT", idat);
  put_chunk(png, "IEND", {});
  return png;
}

UtiaImageAngles grid_angles(const Vec3d& light, const Vec3d& view) {
  auto theta = [](const Vec3d& d) { return std::acos(std::clamp(d.z, -1.0, 1.0)) / kDeg; };
  auto phi = [](const Vec3d& d) {
    const double p = std::atan2(d.y, d.x) / kDeg;
    return p < 0 ? p + 360.0 : p;
  };
  return {theta(light), phi(light), theta(view), phi(view)};
}

std::string angle_text(double a) {
  return a == std::floor(a) ? fmt::format("{:03d}", static_cast<int>(a)) : fmt::format("{}", a);
}

}  // namespace

std::optional<UtiaImageAngles> parse_utia_image_name(std::string_view file_name) {
  const std::string name = lower(file_name);
  std::string_view s = name;
  UtiaImageAngles a;
  std::optional<double> v;
  if (!consume(s, "tl") || !(v = parse_angle(s))) return std::nullopt;
  a.theta_light = *v;
  if (!consume(s, "_pl") || !(v = parse_angle(s))) return std::nullopt;
  a.phi_light = *v;
  if (!consume(s, "_tv") || !(v = parse_angle(s))) return std::nullopt;
  a.theta_view = *v;
  if (!consume(s, "_pv") || !(v = parse_angle(s))) return std::nullopt;
  a.phi_view = *v;
  if (s != ".png" && s != ".exr") return std::nullopt;
  if (a.theta_light > 90 || a.theta_view > 90 || a.phi_light >= 360 || a.phi_view >= 360)
    return std::nullopt;
  return a;
}

std::string utia_image_name(const UtiaImageAngles& a, std::string_view extension) {
  auto wrap = [](double phi) {
    const long p = std::lround(phi) % 360;
    return p < 0 ? p + 360 : p;
  };
  return fmt::format("tl{:03d}_pl{:03d}_tv{:03d}_pv{:03d}.{}", std::lround(a.theta_light),
                     wrap(a.phi_light), std::lround(a.theta_view), wrap(a.phi_view), extension);
}

MeasuredBtf read_utia_btf(const fs::path& directory, const MeasuredImportOptions& options) {
  std::error_code ec;
  if (!fs::exists(directory, ec)) throw InputError(directory, "not found");
  if (!fs::is_directory(directory, ec))
    throw InputError(directory, "not a directory (a UTIA BTF is a directory of images)");

  struct Entry {
    UtiaImageAngles angles;
    fs::path file;
  };
  std::vector<Entry> entries;
  for (const fs::directory_entry& e : fs::directory_iterator(directory, ec)) {
    if (!e.is_regular_file(ec)) continue;
    const fs::path& file = e.path();
    if (!is_image_extension(lower(file.extension().string()))) continue;
    const auto angles = parse_utia_image_name(file.filename().string());
    if (!angles)
      throw InputError(file,
                       "name does not match tl<theta>_pl<phi>_tv<theta>_pv<phi>.png|exr (angles "
                       "in degrees, theta in [0, 90], phi in [0, 360))");
    entries.push_back({*angles, file});
  }
  if (ec) throw InputError(directory, fmt::format("cannot list: {}", ec.message()));
  if (entries.empty()) throw InputError(directory, "holds no .png or .exr images");
  std::sort(entries.begin(), entries.end(),
            [](const Entry& a, const Entry& b) { return a.file.filename() < b.file.filename(); });

  using Key = std::pair<double, double>;
  std::map<Key, int> light_index, view_index;
  for (const Entry& e : entries) {
    light_index.emplace(Key{e.angles.theta_light, e.angles.phi_light}, 0);
    view_index.emplace(Key{e.angles.theta_view, e.angles.phi_view}, 0);
  }
  MeasuredSource source;
  source.file = directory;
  for (auto& [k, i] : light_index) {
    i = static_cast<int>(source.lights.size());
    source.lights.push_back(direction_from_angles(k.first * kDeg, k.second * kDeg));
  }
  for (auto& [k, i] : view_index) {
    i = static_cast<int>(source.views.size());
    source.views.push_back(direction_from_angles(k.first * kDeg, k.second * kDeg));
  }
  // Every light x view pair once: duplicates and missing pairs are found on the entries
  // themselves, so that names sharing no angles (n files, n lights x n views pairs) cost
  // O(n log n), not an n^2 table.
  std::map<std::pair<Key, Key>, const Entry*> present;  // (light, view) -> entry
  for (const Entry& e : entries) {
    const auto [it, inserted] = present.try_emplace({Key{e.angles.theta_light, e.angles.phi_light},
                                                     Key{e.angles.theta_view, e.angles.phi_view}},
                                                    &e);
    if (!inserted)
      throw InputError(e.file, fmt::format("has the same four angles as {}; keep one of them",
                                           it->second->file.filename().string()));
  }
  const std::size_t nl = light_index.size(), nv = view_index.size();
  // nl, nv <= present.size(): the product is compared without overflow.
  if (nl > present.size() / nv || nl * nv != present.size()) {
    // More pairs than images: the first missing one in (view, light) order lies among the
    // first present.size() + 1 pairs.
    for (const auto& [vk, v] : view_index) {
      for (const auto& [lk, l] : light_index) {
        if (present.count({lk, vk}) != 0) continue;
        const std::string name =
            fmt::format("tl{}_pl{}_tv{}_pv{}.png", angle_text(lk.first), angle_text(lk.second),
                        angle_text(vk.first), angle_text(vk.second));
        throw InputError(
            directory / name,
            fmt::format("missing (or its .exr): the directory has images for this light and for "
                        "this view, and a UTIA BTF needs every light x view pair ({} lights x {} "
                        "views in the names, {} images)",
                        nl, nv, present.size()));
      }
    }
    PRT_CHECK(false, "{} lights x {} views but {} distinct pairs and none missing", nl, nv,
              present.size());
  }
  auto files = std::make_shared<std::vector<fs::path>>(nv * nl);
  for (const auto& [key, e] : present) {
    const int l = light_index.at(key.first);
    const int v = view_index.at(key.second);
    (*files)[static_cast<std::size_t>(v) * nl + l] = e->file;
  }

  const RgbImage first = read_tile_image(files->front());
  if (first.width != first.height)
    throw InputError(files->front(), fmt::format("is {} x {}; a UTIA tile must be square",
                                                 first.width, first.height));
  const int w = first.width;
  // The options and the size of the import, before any other image is read.
  check_measured_import(directory, w, options);
  source.resolution = w;
  source.cosine_in_data = true;
  source.tile = [files, nl, w](int view, int light, std::span<float> tile) {
    const fs::path& file = (*files)[static_cast<std::size_t>(view) * nl + light];
    const RgbImage img = read_tile_image(file);
    if (img.width != w || img.height != w)
      throw InputError(file, fmt::format("is {} x {}, the other images are {} x {}", img.width,
                                         img.height, w, w));
    for (int row = 0; row < w; ++row) {
      for (int col = 0; col < w; ++col) {
        const Rgb& p = img.at(col, row);
        float* dst = tile.data() + (static_cast<std::size_t>(w - 1 - row) * w + col) * 3;
        dst[0] = p.r;
        dst[1] = p.g;
        dst[2] = p.b;
      }
    }
  };
  source.tile_file = [files, nl](int view, int light) {
    return (*files)[static_cast<std::size_t>(view) * nl + light];
  };
  fs::path base = directory.lexically_normal();
  if (base.filename().empty()) base = base.parent_path();
  source.material = "utia:" + base.filename().string();
  source.parameters = {{"source_format", "utia"}, {"source", directory.string()}};
  return resample_measured(source, options);
}

UtiaWriteReport write_utia_btf(const Btf& btf, const fs::path& directory,
                               const UtiaWriteOptions& options) {
  if (!std::isfinite(options.png_scale) || options.png_scale <= 0)
    throw ParameterError(fmt::format("PNG scale {} must be finite and > 0", options.png_scale));
  std::error_code ec;
  if (fs::exists(directory, ec) &&
      (!fs::is_directory(directory, ec) || !fs::is_empty(directory, ec)))
    throw ParameterError(
        fmt::format("{}: exists and is not an empty directory; remove it or choose another",
                    directory.string()));
  const HemisphereGrid views(btf.view_side()), lights(btf.light_side());
  const std::vector<double> projected = lights.projected_solid_angles();
  const double omega = lights.cell_solid_angle();
  const int u = btf.resolution();
  const bool png = options.format == UtiaImageFormat::kPng16;
  const std::string ext = png ? "png" : "exr";

  std::vector<std::string> names(static_cast<std::size_t>(btf.view_count()) * btf.light_count());
  std::vector<double> divisor(btf.light_count());
  std::set<std::string> seen;
  for (int v = 0; v < btf.view_count(); ++v) {
    for (int l = 0; l < btf.light_count(); ++l) {
      const UtiaImageAngles a = grid_angles(lights.direction(l), views.direction(v));
      std::string name = utia_image_name(a, ext);
      if (!seen.insert(name).second)
        throw ParameterError(fmt::format(
            "grid directions too close for integer-degree names: two images would be {} "
            "(view side {}, light side {})",
            name, btf.view_side(), btf.light_side()));
      names[static_cast<std::size_t>(v) * btf.light_count() + l] = std::move(name);
      if (v == 0) {
        const double named_cos = std::cos(static_cast<double>(std::lround(a.theta_light)) * kDeg);
        if (options.cosine == LightCosine::kCellMean && named_cos < kMinNamedCosine)
          throw ParameterError(fmt::format(
              "light {} rounds to the horizon in its name; its cosine cannot be divided out "
              "(use a smaller light side or the as-stored light cosine)",
              l));
        divisor[l] = measured_value_factor(options.cosine, true, projected[l] / omega, named_cos);
      }
    }
  }

  UtiaWriteReport report;
  write_file_atomically(directory, [&](const fs::path& tmp) {
    // write_file_atomically removes a failed temporary file, not a directory of them.
    struct RemoveOnFailure {
      const fs::path& dir;
      bool done = false;
      ~RemoveOnFailure() {
        std::error_code ignored;
        if (!done) fs::remove_all(dir, ignored);
      }
    } cleanup{tmp};
    fs::create_directories(tmp);
    RgbImage image(u, u);
    std::vector<std::uint16_t> samples(static_cast<std::size_t>(u) * u * 3);
    for (int v = 0; v < btf.view_count(); ++v) {
      for (int l = 0; l < btf.light_count(); ++l) {
        const fs::path file = tmp / names[static_cast<std::size_t>(v) * btf.light_count() + l];
        for (int row = 0; row < u; ++row) {
          for (int col = 0; col < u; ++col) {
            const Rgb b = btf.value((u - 1 - row) * u + col, v, l);
            Rgb& p = image.at(col, row);
            for (int c = 0; c < 3; ++c)
              p[c] = divisor[l] == 1.0 ? b[c] : static_cast<float>(b[c] / divisor[l]);
          }
        }
        if (!png) {
          write_exr(image, file);
        } else {
          for (std::size_t i = 0; i < image.pixels.size(); ++i) {
            for (int c = 0; c < 3; ++c) {
              const double q = std::round(image.pixels[i][c] / options.png_scale * 65535.0);
              const bool ok = std::isfinite(q) && q >= 0 && q <= 65535;
              if (!ok) ++report.clipped;
              samples[i * 3 + c] =
                  static_cast<std::uint16_t>(ok ? q : (std::isfinite(q) && q > 0 ? 65535 : 0));
            }
          }
          const std::vector<unsigned char> bytes = encode_png16(u, u, samples);
          std::ofstream out(file, std::ios::binary | std::ios::trunc);
          if (!out) throw InputError(file, "cannot open for writing");
          out.write(reinterpret_cast<const char*>(bytes.data()),
                    static_cast<std::streamsize>(bytes.size()));
          out.close();
          if (!out) throw InputError(file, "write failed (disk full?)");
        }
        ++report.images;
      }
    }
    cleanup.done = true;
  });
  return report;
}

}  // namespace prt
