/*
 * image_io_oiio.cpp — the OpenImageIO side of src/io: the project's only C++ translation unit in src/io.
 *
 * It is built as a module of its own (libmatremap-oiio.so) that oiio_module.c loads with dlopen the first time
 * an image is read or a non-EXR image written: Debian's OpenImageIO pulls in some 250 shared libraries whose
 * start-up (OpenCV's above all) costs about 0.4 s, which every `matremap` run would otherwise pay, even
 * `matremap models`. The module exports five extern "C" entry points (contracts of mr_io_oiio_read,
 * mr_io_oiio_read_as, mr_io_oiio_read_memory and mr_io_oiio_write in io_internal.h): mr_oiio_module_read decodes a
 * file of any format OpenImageIO 2.4 knows into floats, mr_oiio_module_read_as a file by the one reader its caller
 * names, mr_oiio_module_read_memory does the same for encoded bytes in memory (an
 * IOMemReader), mr_oiio_module_write encodes an already-quantised buffer and writes it through the atomic protocol of
 * atomic_file.c (compiled into the module too), and mr_oiio_module_last_error returns the module's own
 * thread-local message (status.c is compiled into the module with hidden visibility, so the module's
 * mr_fail writes there; the loader copies it into the library's). Everything else (option checks, channel
 * conversion, sRGB coding and quantisation) is C (image_io.c), so this file stays a thin shim. No C++
 * exception crosses the boundary: each entry point catches everything and maps it to an mr_status with a
 * message naming the file (or the name the caller gives bytes in memory).
 *
 * OpenImageIO facts relied on (OpenImageIO 2.4 documentation, "ImageInput"/"ImageOutput" and the format
 * plugin notes):
 *   - "oiio:UnassociatedAlpha" = 1 in the open() configuration keeps PNG/TIFF alpha unassociated on read
 *     (otherwise colour is premultiplied); on an output spec it declares our data unassociated, so the PNG
 *     writer does not divide colour by alpha.
 *   - The spec is known after open(), before any pixel is decoded: the size limit is enforced there.
 *   - read_image(subimage, miplevel, chbegin, chend, TypeFloat, ...) converts integer samples to [0,1]
 *     (v / (2^bits - 1)); floating-point data is returned as stored.
 *   - A reader reads from memory when its open() configuration carries the IOProxy as "oiio:ioproxy" (a proxy
 *     given to create() alone is dropped by open(), which then looks for a file); PNG, JPEG, TIFF, OpenEXR, HDR,
 *     WebP, GIF and BMP support it (supports("ioproxy"), checked on OpenImageIO 2.4.7).
 *   - Error text accumulates per ImageInput/ImageOutput (geterror()) or, for failed open/create, globally per
 *     thread (OIIO::geterror()); it is always retrieved, which also clears it.
 */
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <cstdint>
#include <cstdlib>
#include <climits>
#include <cstring>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "../mr_internal.h"
#include "io_internal.h"

namespace {

/* The module decodes and encodes on the calling thread. matremap's own loops decide how many images are read or
 * written at once (--threads, OMP_NUM_THREADS), and many copies of the tool run side by side; OpenEXR's pool,
 * which OpenImageIO sizes to one thread per core by default, would add threads nobody asked for (its reader
 * started them whatever --threads said: tests/threads_cli.sh). "exr_threads" -1 is OpenEXR on the caller's
 * thread (0 would be one per core); set when the module is loaded, before any file is opened. OpenImageIO's own
 * pool ("threads") is left alone: reading and writing whole images does not use it, and setting it starts it. */
const bool exr_on_the_calling_thread = [] { return OIIO::attribute("exr_threads", -1); }();

/* OIIO messages may span lines; mr_last_error is one line. */
std::string one_line(std::string text) {
    for (char &ch : text)
        if (ch == '\n' || ch == '\r') ch = ' ';
    while (!text.empty() && text.back() == ' ') text.pop_back();
    if (text.empty()) text = "no reason given";
    return text;
}

int find_channel(const OIIO::ImageSpec &spec, const char *name) {
    for (int c = 0; c < spec.nchannels; c++)
        if (spec.channel_name(c) == name) return c;
    return -1;
}

/* Channel indices of the stored layout to return: grey, grey+alpha, RGB or RGBA (io_internal.h). */
int choose_channels(const OIIO::ImageSpec &spec, int index[4]) {
    const int n = spec.nchannels;
    int alpha = spec.alpha_channel >= 0 && spec.alpha_channel < n ? spec.alpha_channel : find_channel(spec, "A");
    if (n == 1) {
        index[0] = 0;
        return 1;
    }
    if (n == 2) {
        if (alpha < 0) alpha = 1; /* two channels are grey + alpha by convention (PNG, TIFF) */
        index[0] = alpha == 0 ? 1 : 0;
        index[1] = alpha;
        return 2;
    }
    int r = find_channel(spec, "R"), g = find_channel(spec, "G"), b = find_channel(spec, "B");
    if (r < 0 || g < 0 || b < 0) {
        /* No R,G,B names (e.g. a TIFF with generic names): the first three non-alpha channels. */
        int k = 0;
        for (int c = 0; c < n && k < 3; c++)
            if (c != alpha) index[k++] = c;
        r = index[0];
        g = index[1];
        b = index[2];
    }
    index[0] = r;
    index[1] = g;
    index[2] = b;
    if (alpha >= 0) {
        index[3] = alpha;
        return 4;
    }
    return 3;
}

OIIO::TypeDesc sample_type(mr_io_sample sample) {
    switch (sample) {
    case MR_IO_U8: return OIIO::TypeDesc::UINT8;
    case MR_IO_U16: return OIIO::TypeDesc::UINT16;
    default: return OIIO::TypeDesc::FLOAT;
    }
}

/* The most channels a file may declare (an EXR with render passes as layers has a few dozen). */
const int MAX_CHANNELS = 1024;

/* How far a data window's origin may lie from (0, 0): OpenImageIO computes x + width, y + height in int. */
const int64_t MAX_ORIGIN = (int64_t)1 << 30;

/* The spec's claims, checked before a byte of pixels is allocated or decoded: sizes within max_dimension, a data
 * window whose ends fit in int, a sane channel count and tile size; volume and deep images refused, and an EXR of
 * several parts (OpenImageIO would read its first part only, which may not be the one meant). */
mr_status check_spec(OIIO::ImageInput *in, const char *label, int max_dimension, bool is_exr) {
    const OIIO::ImageSpec &spec = in->spec();
    if (spec.width < 1 || spec.height < 1 || spec.nchannels < 1)
        return mr_fail(MR_ERR_FORMAT, "%s: empty image (%dx%d, %d channels)", label, spec.width, spec.height,
                       spec.nchannels);
    if (spec.width > max_dimension || spec.height > max_dimension)
        return mr_fail(MR_ERR_FORMAT, "%s: %dx%d pixels exceeds the maximum dimension %d", label, spec.width,
                       spec.height, max_dimension);
    if (spec.depth > 1)
        return mr_fail(MR_ERR_FORMAT, "%s: volume images (depth %d) are not supported", label, spec.depth);
    if (spec.deep) return mr_fail(MR_ERR_FORMAT, "%s: deep images are not supported", label);
    if (spec.nchannels > MAX_CHANNELS)
        return mr_fail(MR_ERR_FORMAT, "%s: %d channels, more than the limit of %d", label, spec.nchannels,
                       MAX_CHANNELS);
    const int64_t x = spec.x, y = spec.y;
    if (x < -MAX_ORIGIN || y < -MAX_ORIGIN || x + spec.width > MAX_ORIGIN || y + spec.height > MAX_ORIGIN ||
        spec.z != 0)
        return mr_fail(MR_ERR_FORMAT, "%s: data window at (%d, %d, %d), size %dx%d, lies beyond +-2^30 pixels", label,
                       spec.x, spec.y, spec.z, spec.width, spec.height);
    if (spec.tile_width != 0 && (spec.tile_width < 0 || spec.tile_height < 1 || spec.tile_width > max_dimension ||
                                 spec.tile_height > max_dimension || spec.tile_depth > 1))
        return mr_fail(MR_ERR_FORMAT, "%s: tiles of %dx%dx%d pixels (each side at most %d)", label, spec.tile_width,
                       spec.tile_height, spec.tile_depth, max_dimension);
    if (is_exr) {
        int parts = 1;
        while (parts < 1000 && in->seek_subimage(parts, 0))
            parts++;
        (void)in->geterror(); // seeking past the last part records an error
        if (parts > 1)
            return mr_fail(MR_ERR_UNSUPPORTED,
                           "%s: a multi-part EXR (%s%d parts); extract the one to read, e.g. "
                           "oiiotool FILE --subimage 0 -o part.exr",
                           label, parts == 1000 ? "at least " : "", parts);
        if (!in->seek_subimage(0, 0)) {
            std::string why = one_line(in->geterror());
            return mr_fail(MR_ERR_FORMAT, "%s: cannot read its first part: %s", label, why.c_str());
        }
    }
    return MR_OK;
}

/* The first subimage of the opened `in` into *raw; messages call the image `label`. */
mr_status decode(OIIO::ImageInput *in, const char *label, int max_dimension, mr_io_raw *raw) {
    const bool is_exr = std::strcmp(in->format_name(), "openexr") == 0;
    mr_status status = check_spec(in, label, max_dimension, is_exr);
    if (status != MR_OK)
        return status;
    const OIIO::ImageSpec spec = in->spec();

    int index[4] = {0, 0, 0, 0};
    const int channels = choose_channels(spec, index);
    const size_t count = (size_t)spec.width * (size_t)spec.height;
    /* All channels are read, row by row (read_scanline) or by rows of tiles (read_tiles), in the stored type when
     * every channel has the same one (converted here), else as floats: OpenImageIO 2.4's read_image and
     * read_scanlines allocate a 64 MB buffer per call whatever the image's size (almost all the time a fuzzer spent
     * on a 24x24 JPEG), which these do not; they are also faster on large files. */
    const bool one_type = spec.channelformats.empty();
    const OIIO::TypeDesc type = one_type ? spec.format : OIIO::TypeFloat;
    const size_t span = (size_t)spec.nchannels, sample_size = type.size();
    const int lo = 0;
    if (count > SIZE_MAX / sizeof(float) / span)
        return mr_fail(MR_ERR_NOMEM, "%s: %dx%d pixels do not fit in memory", label, spec.width, spec.height);
    /* A band of rows at a time, each band into memory of its own allocated as it is reached, its errors checked
     * before the next: a file that claims more rows than it holds (a JPEG or HDR header saying 16000 x 16000 over
     * a few bytes of data) fails at its first missing band with the decoder's error, having cost one band, instead
     * of 3 GB allocated and filled with grey first. The bands are held by unique_ptrs (the stored type's bytes by
     * a vector, one band long), so an exception thrown by OIIO cannot leak them; `pixels` is malloc'ed only once
     * nothing below can throw (the caller releases it with free()). */
    const int tile = spec.tile_width > 0 ? spec.tile_height : 1;
    const int band = tile >= 256 ? tile : (256 + tile - 1) / tile * tile; // whole tiles, at least 256 rows
    const size_t row_values = (size_t)spec.width * span, row_bytes = row_values * sample_size;
    if ((size_t)band * row_values > (size_t)INT_MAX) // convert_pixel_values counts in int
        return mr_fail(MR_ERR_NOMEM, "%s: %dx%d pixels of %d channels do not fit in memory", label, spec.width,
                       spec.height, spec.nchannels);
    std::vector<unsigned char> native(one_type ? (size_t)(band < spec.height ? band : spec.height) * row_bytes : 0);
    std::vector<std::unique_ptr<float[]>> bands;
    for (int y = 0; y < spec.height; y += band) {
        const int rows = spec.height - y < band ? spec.height - y : band;
        bands.emplace_back(new float[(size_t)rows * row_values]); // not cleared: the decoder fills it
        float *at = bands.back().get();
        unsigned char *target = one_type ? native.data() : reinterpret_cast<unsigned char *>(at);
        bool ok = true;
        if (spec.tile_width > 0)
            ok = in->read_tiles(0, 0, spec.x, spec.x + spec.width, spec.y + y, spec.y + y + rows, spec.z, spec.z + 1,
                                0, spec.nchannels, type, target);
        for (int r = 0; ok && spec.tile_width <= 0 && r < rows; r++)
            ok = in->read_scanline(spec.y + y + r, spec.z, type, target + (size_t)r * row_bytes);
        if (ok && one_type)
            ok = OIIO::convert_pixel_values(type, native.data(), OIIO::TypeFloat, at, (int)((size_t)rows * row_values));
        if (!ok) {
            std::string why = one_line(in->geterror());
            return mr_fail(MR_ERR_FORMAT, "%s: cannot decode pixels (corrupt or truncated?): %s", label, why.c_str());
        }
        /* A decoder may record a failure and still return true: libjpeg's "Premature end of JPEG file" on a
         * truncated JPEG is only a warning, and the missing rows come back grey. Any pending message fails the
         * read (this also leaves nothing pending when the ImageInput is destroyed). */
        if (in->has_error())
            return mr_fail(MR_ERR_FORMAT, "%s: decoded with errors (corrupt or truncated?): %s", label,
                           one_line(in->geterror()).c_str());
    }
    in->close();
    std::string pending = in->geterror();
    if (!pending.empty())
        return mr_fail(MR_ERR_FORMAT, "%s: decoded with errors (corrupt or truncated?): %s", label,
                       one_line(pending).c_str());
    float *pixels = static_cast<float *>(std::malloc(count * (size_t)channels * sizeof(float)));
    if (pixels == nullptr)
        return mr_fail(MR_ERR_NOMEM, "%s: out of memory for %dx%d pixels", label, spec.width, spec.height);
    const size_t band_pixels = (size_t)band * (size_t)spec.width;
    for (size_t p = 0; p < count; p++) {
        const float *from = bands[p / band_pixels].get() + (p % band_pixels) * span;
        for (int k = 0; k < channels; k++)
            pixels[p * (size_t)channels + (size_t)k] = from[index[k] - lo];
    }

    /* Integer storage holds display-encoded values, except in EXR, which is linear whatever the type. */
    raw->width = spec.width;
    raw->height = spec.height;
    raw->channels = channels;
    raw->encoded = !spec.format.is_floating_point() && !is_exr;
    raw->bits = spec.format == OIIO::TypeDesc::UINT8 ? 8 : (spec.format == OIIO::TypeDesc::UINT16 ? 16 : 0);
    raw->pixels = pixels;
    return MR_OK;
}

/* Reading configuration: alpha unassociated (PNG/TIFF colour is not premultiplied on read). */
OIIO::ImageSpec read_config() {
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    return config;
}

mr_status read_impl(const char *path, const char *label, int max_dimension, mr_io_raw *raw) {
    const OIIO::ImageSpec config = read_config();
    auto in = OIIO::ImageInput::open(path, &config);
    if (!in) {
        std::string why = one_line(OIIO::geterror());
        return mr_fail(MR_ERR_FORMAT, "%s: not a readable image: %s", label, why.c_str());
    }
    return decode(in.get(), label, max_dimension, raw);
}

/* The reader named `format` (a signature's: image_io.c) made, opened on `name` with `config` and decoded:
 * `memory`, if not NULL, is where it reads from (the proxy is in `config` too). Never the other readers
 * OpenImageIO would try on a file its named reader refuses. */
mr_status read_named(const char *format, const char *name, const OIIO::ImageSpec &config,
                     OIIO::Filesystem::IOProxy *memory, const char *label, int max_dimension, mr_io_raw *raw) {
    auto in = OIIO::ImageInput::create(format, false, &config, memory);
    if (!in) {
        std::string why = one_line(OIIO::geterror());
        return mr_fail(MR_ERR_EXTERNAL, "%s: OpenImageIO has no %s reader: %s", label, format, why.c_str());
    }
    if (memory != nullptr && !in->supports("ioproxy"))
        return mr_fail(MR_ERR_UNSUPPORTED, "%s: the OpenImageIO %s reader cannot read from memory", label, format);
    OIIO::ImageSpec opened;
    if (!in->open(name, opened, config)) {
        std::string why = one_line(in->geterror());
        (void)OIIO::geterror();
        return mr_fail(MR_ERR_FORMAT, "%s: not a readable %s image: %s", label, in->format_name(), why.c_str());
    }
    return decode(in.get(), label, max_dimension, raw);
}

/* A file by the reader named `format`, read from the disk as the reader goes (not held whole). */
mr_status read_as_impl(const char *path, const char *format, const char *label, int max_dimension, mr_io_raw *raw) {
    return read_named(format, path, read_config(), nullptr, label, max_dimension, raw);
}

/* Bytes in memory through an IOMemReader, which must outlive the reader (declared first). The proxy goes in the
 * configuration ("oiio:ioproxy"): open() takes it from there, and without it OIIO 2.4.7 looks for a file named
 * `label`. The reader is chosen by name, as bytes have no extension for OpenImageIO to go by. */
mr_status read_memory_impl(const void *bytes, size_t size, const char *format, const char *label, int max_dimension,
                           mr_io_raw *raw) {
    OIIO::Filesystem::IOMemReader memory(bytes, size);
    OIIO::ImageSpec config = read_config();
    void *proxy = &memory;
    config.attribute("oiio:ioproxy", OIIO::TypeDesc::PTR, &proxy);
    return read_named(format, label, config, &memory, label, max_dimension, raw);
}

/* Removes the temporary file if the write does not reach commit, even when an exception unwinds. */
struct atomic_guard {
    mr_atomic_file file;
    ~atomic_guard() { mr_atomic_abort(&file); }
};

/* open + write_image + close, then insist that no error message is pending (some OIIO writers record a
 * failure and still return true). */
bool encode(OIIO::ImageOutput &out, const char *name, const OIIO::ImageSpec &spec, OIIO::TypeDesc type,
            const void *data, std::string &why) {
    bool ok = out.open(name, spec) && out.write_image(type, data);
    ok = out.close() && ok;
    why = out.geterror();
    return ok && why.empty();
}

mr_status write_impl(const char *path, int width, int height, int channels, mr_io_sample sample, const void *data,
                     int srgb_tag, int jpeg_quality) {
    /* Declared before the writer, so they outlive it whatever path returns. */
    std::vector<unsigned char> encoded;
    OIIO::Filesystem::IOVecOutput proxy(encoded);
    auto out = OIIO::ImageOutput::create(path);
    if (!out) {
        std::string why = one_line(OIIO::geterror());
        return mr_fail(MR_ERR_UNSUPPORTED, "image '%s': no OpenImageIO writer for this extension: %s", path,
                       why.c_str());
    }
    const OIIO::TypeDesc type = sample_type(sample);
    OIIO::ImageSpec spec(width, height, channels, type);
    spec.alpha_channel = channels == 4 ? 3 : -1;
    spec.attribute("oiio:UnassociatedAlpha", 1);
    if (srgb_tag) spec.attribute("oiio:ColorSpace", "sRGB");
    const std::string format = out->format_name();
    /* OIIO 2.4.7's TIFF writer reports spurious "failed TIFFWriteCustomDirectory() of the Exif data" errors */
    if (format == "tiff") spec.attribute("tiff:write_exif", 0);
    if (format == "jpeg") {
        spec.attribute("Compression", "jpeg:" + std::to_string(jpeg_quality));
        spec.attribute("CompressionQuality", jpeg_quality);
    }
    std::string why;

    if (format == "tiff") {
        /* libtiff checks every write itself, but OIIO 2.4.7's TIFF writer cannot target an IOVecOutput set
         * after create() (the file lacks ImageLength): write the temporary file directly. */
        atomic_guard guard;
        mr_status status = mr_atomic_begin(path, &guard.file);
        if (status != MR_OK) return status;
        if (!encode(*out, guard.file.tmp_path, spec, type, data, why))
            return mr_fail(MR_ERR_IO, "image '%s': cannot write %s: %s", path, format.c_str(), one_line(why).c_str());
        return mr_atomic_commit(&guard.file);
    }

    /* Everything else is encoded in memory (io_internal.h says why) and written with checked stdio. */
    if (!out->supports("ioproxy") || !out->set_ioproxy(&proxy)) {
        (void)out->geterror();
        return mr_fail(MR_ERR_UNSUPPORTED, "image '%s': the OpenImageIO %s writer cannot encode to memory", path,
                       format.c_str());
    }
    if (!encode(*out, path, spec, type, data, why))
        return mr_fail(MR_ERR_EXTERNAL, "image '%s': OpenImageIO cannot encode %s: %s", path, format.c_str(),
                       one_line(why).c_str());
    if (encoded.empty())
        return mr_fail(MR_ERR_EXTERNAL, "image '%s': OpenImageIO produced no %s data", path, format.c_str());
    return mr_atomic_write_bytes(path, encoded.data(), encoded.size());
}

/* Runs `body` (returning an mr_status) so that no exception leaves the module: each becomes a status and a message
 * naming `label` and what was being done ("decoding", "encoding"). */
template <typename F> mr_status guarded(const char *label, const char *doing, F body) {
    try {
        return body();
    } catch (const std::bad_alloc &) {
        return mr_fail(MR_ERR_NOMEM, "%s: out of memory while %s", label, doing);
    } catch (const std::exception &e) {
        return mr_fail(MR_ERR_EXTERNAL, "%s: OpenImageIO failed: %s", label, e.what());
    } catch (...) {
        return mr_fail(MR_ERR_EXTERNAL, "%s: OpenImageIO failed with an unknown exception", label);
    }
}

} // namespace

#define MR_MODULE_EXPORT __attribute__((visibility("default")))

extern "C" MR_MODULE_EXPORT const char *mr_oiio_module_last_error(void) { return mr_last_error(); }

extern "C" MR_MODULE_EXPORT mr_status mr_oiio_module_read(const char *path, int max_dimension, mr_io_raw *raw) {
    char label[MR_IO_LABEL_SIZE];
    mr_io_file_label(label, path);
    return guarded(label, "decoding", [&] { return read_impl(path, label, max_dimension, raw); });
}

extern "C" MR_MODULE_EXPORT mr_status mr_oiio_module_read_as(const char *path, const char *format, int max_dimension,
                                                             mr_io_raw *raw) {
    char label[MR_IO_LABEL_SIZE];
    mr_io_file_label(label, path);
    return guarded(label, "decoding", [&] { return read_as_impl(path, format, label, max_dimension, raw); });
}

extern "C" MR_MODULE_EXPORT mr_status mr_oiio_module_read_memory(const void *bytes, size_t size, const char *format,
                                                                 const char *label, int max_dimension,
                                                                 mr_io_raw *raw) {
    return guarded(label, "decoding",
                   [&] { return read_memory_impl(bytes, size, format, label, max_dimension, raw); });
}

extern "C" MR_MODULE_EXPORT mr_status mr_oiio_module_write(const char *path, int width, int height, int channels,
                                                           mr_io_sample sample, const void *data, int srgb_tag,
                                                           int jpeg_quality) {
    char label[MR_IO_LABEL_SIZE];
    mr_io_file_label(label, path);
    return guarded(label, "encoding",
                   [&] { return write_impl(path, width, height, channels, sample, data, srgb_tag, jpeg_quality); });
}
