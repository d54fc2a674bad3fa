// PNG output and image arithmetic for `kodawari render`: box-filter shrinking and
// contact sheets.

#include <algorithm>
#include <cassert>
#include <vector>

#include "kodawari/core/atomic_file.hpp"
#include "kodawari/render/renderer.hpp"

namespace kodawari::render {

// engine/render/stb_image_write_impl.cpp: stb's writer, behind a function so that only
// that file sees stb's internals.
using StbWriteFunc = void(void* context, void* data, int size);
int stb_png_to_func(StbWriteFunc* write, void* context, int width, int height, const void* rgba);

Result<void> write_png(const std::string& path, const Image& image) {
    assert(image.rgba.size() == std::size_t{image.width} * image.height * 4);
    std::vector<unsigned char> png;
    const auto append = [](void* context, void* data, int size) {
        auto* bytes = static_cast<std::vector<unsigned char>*>(context);
        const auto* begin = static_cast<const unsigned char*>(data);
        bytes->insert(bytes->end(), begin, begin + size);
    };
    if (stb_png_to_func(append, &png, static_cast<int>(image.width), static_cast<int>(image.height), image.rgba.data()) == 0) {
        return make_error(Error::Kind::Internal, path + ": PNG encoding failed");
    }
    auto file = AtomicFile::open(path);
    if (!file) return file.error();
    file.value().write(png.data(), png.size());
    return file.value().commit();
}

Image downscale(const Image& image, std::uint32_t width, std::uint32_t height) {
    assert(width > 0 && height > 0 && image.width > 0 && image.height > 0);
    Image out;
    out.width = width;
    out.height = height;
    out.rgba.resize(std::size_t{width} * height * 4);
    for (std::uint32_t y = 0; y < height; ++y) {
        // Source rows [y0, y1): every source pixel belongs to exactly one target pixel.
        const std::uint32_t y0 = static_cast<std::uint32_t>(std::uint64_t{y} * image.height / height);
        const std::uint32_t y1 = std::max(y0 + 1, static_cast<std::uint32_t>(std::uint64_t{y + 1} * image.height / height));
        for (std::uint32_t x = 0; x < width; ++x) {
            const std::uint32_t x0 = static_cast<std::uint32_t>(std::uint64_t{x} * image.width / width);
            const std::uint32_t x1 = std::max(x0 + 1, static_cast<std::uint32_t>(std::uint64_t{x + 1} * image.width / width));
            std::uint32_t sum[4] = {0, 0, 0, 0};
            for (std::uint32_t sy = y0; sy < y1; ++sy) {
                for (std::uint32_t sx = x0; sx < x1; ++sx) {
                    const std::uint8_t* p = image.rgba.data() + (std::size_t{sy} * image.width + sx) * 4;
                    for (int k = 0; k < 4; ++k) sum[k] += p[k];
                }
            }
            const std::uint32_t n = (y1 - y0) * (x1 - x0);
            std::uint8_t* q = out.rgba.data() + (std::size_t{y} * width + x) * 4;
            for (int k = 0; k < 4; ++k) q[k] = static_cast<std::uint8_t>((sum[k] + n / 2) / n);
        }
    }
    return out;
}

Image contact_sheet(std::span<const Image> images, std::uint32_t columns, std::uint32_t cell_width, std::uint32_t cell_height) {
    assert(!images.empty() && columns > 0 && cell_width > 0 && cell_height > 0);
    constexpr std::uint32_t kGutter = 2;
    const auto count = static_cast<std::uint32_t>(images.size());
    columns = std::min(columns, count);
    const std::uint32_t rows = (count + columns - 1) / columns;
    Image sheet;
    sheet.width = columns * cell_width + (columns + 1) * kGutter;
    sheet.height = rows * cell_height + (rows + 1) * kGutter;
    sheet.rgba.assign(std::size_t{sheet.width} * sheet.height * 4, 255);
    for (std::uint32_t i = 0; i < count; ++i) {
        const Image cell = downscale(images[i], cell_width, cell_height);
        const std::uint32_t left = kGutter + (i % columns) * (cell_width + kGutter);
        const std::uint32_t top = kGutter + (i / columns) * (cell_height + kGutter);
        for (std::uint32_t y = 0; y < cell_height; ++y) {
            std::copy_n(cell.rgba.data() + std::size_t{y} * cell_width * 4, std::size_t{cell_width} * 4,
                        sheet.rgba.data() + (std::size_t{top + y} * sheet.width + left) * 4);
        }
    }
    return sheet;
}

}  // namespace kodawari::render
