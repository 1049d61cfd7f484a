// Image file I/O through OpenImageIO. The only translation unit that includes OIIO headers.

#include "core/image/image_io.h"

#include <OpenImageIO/imageio.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/base/errors.h"
#include "core/image/exr_structure.h"

namespace volstyle::core {
namespace {

namespace fs = std::filesystem;

std::string lowerExtension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
    return ext;
}

bool isFloatFormat(const OIIO::TypeDesc& t) {
    return t.basetype == OIIO::TypeDesc::FLOAT || t.basetype == OIIO::TypeDesc::HALF ||
           t.basetype == OIIO::TypeDesc::DOUBLE;
}

/// A file in the temp directory removed when this goes out of scope.
struct TempFile {
    std::string path;
    explicit TempFile(const std::string& ext) {
        std::string pattern = (fs::temp_directory_path() / "volstyle-XXXXXX").string() + ext;
        std::vector<char> buf(pattern.begin(), pattern.end());
        buf.push_back('\0');
        int fd = mkstemps(buf.data(), int(ext.size()));
        if (fd < 0) throw IoError("cannot create a temporary file in " + fs::temp_directory_path().string());
        close(fd);
        path = buf.data();
    }
    ~TempFile() {
        std::error_code ec;
        fs::remove(path, ec);
    }
};

/// Picks a file extension from the first bytes of an image, so uploads need no file name.
std::string sniffExtension(const unsigned char* p, size_t n) {
    auto starts = [&](std::initializer_list<unsigned char> magic) {
        return n >= magic.size() && std::equal(magic.begin(), magic.end(), p);
    };
    if (starts({0x89, 'P', 'N', 'G'})) return ".png";
    if (starts({0xFF, 0xD8, 0xFF})) return ".jpg";
    if (starts({'I', 'I', 42, 0}) || starts({'M', 'M', 0, 42})) return ".tif";
    if (starts({0x76, 0x2F, 0x31, 0x01})) return ".exr";
    if (starts({'#', '?'})) return ".hdr";
    return "";
}

/// A volstyle render's EXR (core/render/exr_layers.h) holds the medium alone in RGBA with its
/// `background` and `transmittance` layers beside it: keep those two (RGB) when both are there.
void readRenderLayers(const OIIO::ImageSpec& spec, const std::vector<float>& pixels, LoadedImage& out) {
    auto channel = [&](const std::string& name) {
        for (int c = 0; c < spec.nchannels; ++c)
            if (spec.channel_name(c) == name) return c;
        return -1;
    };
    int background[3], transmittance[3];
    for (int c = 0; c < 3; ++c) {
        background[c] = channel(std::string("background.") + "RGB"[c]);
        transmittance[c] = channel(std::string("transmittance.") + "RGB"[c]);
        if (background[c] < 0 || transmittance[c] < 0) return;
    }
    const int nch = spec.nchannels, w = out.image.width, h = out.image.height;
    out.background = Image(w, h);
    out.transmittance = Image(w, h);
    for (size_t i = 0; i < out.image.pixelCount(); ++i)
        for (int c = 0; c < 3; ++c) {
            out.background.rgba[4 * i + size_t(c)] = pixels[i * size_t(nch) + size_t(background[c])];
            out.transmittance.rgba[4 * i + size_t(c)] = pixels[i * size_t(nch) + size_t(transmittance[c])];
        }
}

}  // namespace

LoadedImage loadImage(const std::string& path, int maxSide, const ImageHeaderCheck& checkHeader) {
    if (!fs::exists(path)) throw IoError("no such file '" + path + "'");
    // Alpha is a weight, not coverage: keep colours unassociated (OIIO would premultiply).
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) {
        throw IoError("cannot read '" + path + "' as an image: " + OIIO::geterror());
    }
    const OIIO::ImageSpec& spec = in->spec();
    if (spec.width < 1 || spec.height < 1 || spec.width > maxSide || spec.height > maxSide) {
        throw LimitExceeded("'" + path + "' is " + std::to_string(spec.width) + "x" +
                              std::to_string(spec.height) + "; each side must be in [1, " +
                              std::to_string(maxSide) + "]");
    }
    if (spec.depth > 1) throw InvalidArgument("'" + path + "' is a volume image");
    if (checkHeader) checkHeader(spec.width, spec.height);
    const int nch = spec.nchannels;
    std::vector<float> pixels(size_t(spec.width) * spec.height * nch);
    if (!in->read_image(0, 0, 0, nch, OIIO::TypeDesc::FLOAT, pixels.data())) {
        throw IoError("'" + path + "' is corrupt or truncated: " + in->geterror());
    }
    in->close();

    LoadedImage out;
    out.channels = nch;
    out.hasAlpha = spec.alpha_channel >= 0 || nch == 4 || nch == 2;
    out.wasSrgb = !isFloatFormat(spec.format);
    out.image = Image(spec.width, spec.height);
    const int alphaIndex = spec.alpha_channel >= 0 ? spec.alpha_channel : (nch == 4 ? 3 : (nch == 2 ? 1 : -1));
    for (size_t i = 0; i < out.image.pixelCount(); ++i) {
        const float* src = &pixels[i * nch];
        float* dst = &out.image.rgba[i * 4];
        // Grey (1-2 channels) broadcasts to RGB; the colour channels are the first non-alpha ones.
        int colour[3];
        int k = 0;
        for (int c = 0; c < nch && k < 3; ++c)
            if (c != alphaIndex) colour[k++] = c;
        for (int c = 0; c < 3; ++c) {
            float v = src[colour[k == 1 ? 0 : std::min(c, k - 1)]];
            dst[c] = out.wasSrgb ? srgbToLinear(v) : v;
        }
        dst[3] = alphaIndex >= 0 ? src[alphaIndex] : 1.0f;
    }
    readRenderLayers(spec, pixels, out);
    size_t bad = out.image.countNonFinite() + out.background.countNonFinite() + out.transmittance.countNonFinite();
    if (bad > 0) {
        throw InvalidArgument("'" + path + "' contains " + std::to_string(bad) +
                              " non-finite (NaN or Inf) values; fix or clamp them before uploading");
    }
    return out;
}

Image pictureOf(const LoadedImage& loaded) {
    if (!loaded.isRender()) return loaded.image;
    Image picture = loaded.image;
    for (size_t i = 0; i < picture.pixelCount(); ++i) {
        for (size_t c = 0; c < 3; ++c)
            picture.rgba[4 * i + c] += loaded.transmittance.rgba[4 * i + c] * loaded.background.rgba[4 * i + c];
        picture.rgba[4 * i + 3] = 1;
    }
    return picture;
}

LoadedImage loadImageFromMemory(const void* data, size_t size, const std::string& nameHint,
                                int maxSide, const ImageHeaderCheck& checkHeader) {
    std::string ext = sniffExtension(static_cast<const unsigned char*>(data), size);
    if (ext.empty()) {
        throw InvalidArgument("'" + nameHint +
                              "' is not a supported image (PNG, JPEG, TIFF, EXR or HDR)");
    }
    if (ext == ".exr") checkExrStructure(static_cast<const unsigned char*>(data), size, maxSide, nameHint.c_str());
    TempFile tmp(ext);
    {
        std::ofstream f(tmp.path, std::ios::binary);
        f.write(static_cast<const char*>(data), std::streamsize(size));
        if (!f) throw IoError("cannot write a temporary file");
    }
    try {
        return loadImage(tmp.path, maxSide, checkHeader);
    } catch (const Error& e) {
        // Name the upload, not the temporary file, in the message.
        std::string msg = e.what();
        for (size_t pos; (pos = msg.find(tmp.path)) != std::string::npos;)
            msg.replace(pos, tmp.path.size(), nameHint);
        if (dynamic_cast<const InvalidArgument*>(&e)) throw InvalidArgument(msg);
        throw IoError(msg);
    }
}

void saveImage(const std::string& path, const Image& image, const SaveOptions& options) {
    if (image.empty()) throw InvalidArgument("the image is empty");
    const std::string ext = lowerExtension(path);
    const bool isFloatFile = ext == ".exr" || ext == ".hdr";
    const bool isKnown = isFloatFile || ext == ".png" || ext == ".jpg" || ext == ".jpeg" ||
                         ext == ".tif" || ext == ".tiff";
    if (!isKnown) {
        throw InvalidArgument("unsupported extension '" + ext + "' in '" + path +
                              "'; use .png, .jpg, .tif, .exr or .hdr");
    }
    const bool keepAlpha = ext == ".exr" || (options.writeAlpha && ext != ".jpg" && ext != ".jpeg" && ext != ".hdr");
    const int nch = keepAlpha ? 4 : 3;
    const float scale = float(std::exp2(options.exposure));

    std::vector<float> pixels(image.pixelCount() * nch);
    for (size_t i = 0; i < image.pixelCount(); ++i) {
        for (int c = 0; c < 3; ++c) {
            float v = image.rgba[i * 4 + c] * scale;
            if (!isFloatFile) v = options.data ? std::clamp(v, 0.0f, 1.0f) : linearToSrgb(std::clamp(v, 0.0f, 1.0f));
            pixels[i * nch + c] = v;
        }
        if (keepAlpha) pixels[i * nch + 3] = image.rgba[i * 4 + 3];
    }

    OIIO::TypeDesc format = OIIO::TypeDesc::UINT8;
    if (ext == ".exr") format = options.halfFloat ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT;
    else if (ext == ".hdr") format = OIIO::TypeDesc::FLOAT;
    else if (options.bits == 16 && ext != ".jpg" && ext != ".jpeg") format = OIIO::TypeDesc::UINT16;

    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw IoError("no writer for '" + path + "': " + OIIO::geterror());
    OIIO::ImageSpec spec(image.width, image.height, nch, format);
    if (keepAlpha) spec.alpha_channel = 3;
    spec.attribute("oiio:ColorSpace", isFloatFile || options.data ? "linear" : "sRGB");
    if (!isFloatFile) spec.attribute("oiio:UnassociatedAlpha", 1);  // PNG/TIFF alpha is a weight
    if (!out->open(path, spec) ||
        !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) || !out->close()) {
        throw IoError("cannot write '" + path + "': " + out->geterror());
    }
}

void saveExrLayers(const std::string& path, const std::vector<ExrLayer>& layers, bool halfFloat) {
    if (layers.empty() || !layers[0].image || layers[0].image->empty()) throw InvalidArgument("an EXR needs a main image");
    const Image& main = *layers[0].image;
    std::vector<std::string> names;
    std::vector<std::pair<const Image*, int>> sources;  // image and channel of each file channel
    for (const auto& layer : layers) {
        if (!layer.image || layer.image->width != main.width || layer.image->height != main.height)
            throw InvalidArgument("EXR layer '" + layer.name + "' is missing or not the main image's size");
        const char* rgba[] = {"R", "G", "B", "A"};
        for (int c = 0; c < (layer.name.empty() ? 4 : 3); ++c) {
            names.push_back(layer.name.empty() ? rgba[c] : layer.name + "." + rgba[c]);
            sources.emplace_back(layer.image, c);
        }
    }
    const size_t nch = names.size();
    std::vector<float> pixels(main.pixelCount() * nch);
    for (size_t i = 0; i < main.pixelCount(); ++i)
        for (size_t c = 0; c < nch; ++c) pixels[i * nch + c] = sources[c].first->rgba[i * 4 + size_t(sources[c].second)];
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw IoError("no EXR writer for '" + path + "': " + OIIO::geterror());
    OIIO::ImageSpec spec(main.width, main.height, int(nch), halfFloat ? OIIO::TypeDesc::HALF : OIIO::TypeDesc::FLOAT);
    spec.channelnames = names;
    spec.alpha_channel = layers[0].name.empty() ? 3 : -1;
    spec.attribute("oiio:ColorSpace", "linear");
    spec.attribute("compression", "zip");
    if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::FLOAT, pixels.data()) || !out->close())
        throw IoError("cannot write '" + path + "': " + out->geterror());
}

std::string encodeExrLayers(const std::vector<ExrLayer>& layers, bool halfFloat) {
    TempFile tmp(".exr");
    saveExrLayers(tmp.path, layers, halfFloat);
    std::ifstream f(tmp.path, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

std::string encodeImage(const Image& image, const std::string& format, const SaveOptions& options) {
    if (format != "png" && format != "exr" && format != "jpeg")
        throw InvalidArgument("format must be 'png', 'jpeg' or 'exr', got '" + format + "'");
    TempFile tmp(format == "jpeg" ? ".jpg" : "." + format);
    saveImage(tmp.path, image, options);
    std::ifstream f(tmp.path, std::ios::binary);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
}

}  // namespace volstyle::core
