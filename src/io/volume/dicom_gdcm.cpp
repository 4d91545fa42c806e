/*
 * The GDCM side of the DICOM reader: header values, decoded pixel data and
 * DICOMDIR records behind the C interface of dicom.h. Only GDCM parses DICOM;
 * this file turns its objects into plain numbers and strings. No C++
 * exception leaves it.
 */
#include "io/volume/dicom.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <mutex>
#include <set>
#include <string>
#include <vector>

#include <gdcmAttribute.h>
#include <gdcmDataSet.h>
#include <gdcmFile.h>
#include <gdcmGlobal.h>
#include <gdcmImage.h>
#include <gdcmImageHelper.h>
#include <gdcmImageReader.h>
#include <gdcmMediaStorage.h>
#include <gdcmPixelFormat.h>
#include <gdcmReader.h>
#include <gdcmSequenceOfFragments.h>
#include <gdcmSequenceOfItems.h>
#include <gdcmTag.h>
#include <gdcmTrace.h>

namespace {

void
set_err(char *err, size_t len, const char *msg) {
    if (err && len)
        std::snprintf(err, len, "%s", msg);
}

/* The value of a string element, trailing spaces and NULs removed. */
std::string
get_str(const gdcm::DataSet &ds, uint16_t g, uint16_t e) {
    gdcm::Tag t(g, e);
    if (!ds.FindDataElement(t))
        return std::string();
    const gdcm::DataElement &de = ds.GetDataElement(t);
    const gdcm::ByteValue *bv = de.GetByteValue();
    if (!bv || !bv->GetPointer())
        return std::string();
    std::string s(bv->GetPointer(), bv->GetLength());
    while (!s.empty() && (s.back() == ' ' || s.back() == '\0'))
        s.pop_back();
    size_t a = 0;
    while (a < s.size() && s[a] == ' ')
        a++;
    return s.substr(a);
}

void
copy_str(char *dst, size_t cap, const std::string &s) {
    std::snprintf(dst, cap, "%s", s.c_str());
    /* keep listings on one line */
    for (char *p = dst; *p; p++)
        if (*p == '\n' || *p == '\r' || *p == '\t')
            *p = ' ';
}

/* Up to @p n backslash-separated numbers of a DS/IS element; how many were read. */
int
get_nums(const gdcm::DataSet &ds, uint16_t g, uint16_t e, double *out, int n) {
    std::string s = get_str(ds, g, e);
    if (s.empty())
        return 0;
    int k = 0;
    const char *p = s.c_str();
    while (k < n && *p) {
        char *end = nullptr;
        double v = std::strtod(p, &end);
        if (end == p)
            break;
        out[k++] = v;
        p = end;
        while (*p == ' ')
            p++;
        if (*p != '\\')
            break;
        p++;
    }
    return k;
}

/* Frame positions from the Per-frame Functional Groups of an enhanced file. */
double *
frame_positions(const gdcm::DataSet &ds, int frames) {
    const gdcm::Tag per_frame(0x5200, 0x9230), plane_pos(0x0020, 0x9113);
    if (!ds.FindDataElement(per_frame))
        return nullptr;
    gdcm::SmartPointer<gdcm::SequenceOfItems> sq = ds.GetDataElement(per_frame).GetValueAsSQ();
    if (!sq || (int)sq->GetNumberOfItems() != frames)
        return nullptr;
    double *pos = static_cast<double *>(std::malloc(sizeof(double) * 3 * (size_t)frames));
    if (!pos)
        return nullptr;
    for (int i = 0; i < frames; i++) {
        const gdcm::DataSet &item = sq->GetItem((size_t)i + 1).GetNestedDataSet();
        if (!item.FindDataElement(plane_pos)) {
            std::free(pos);
            return nullptr;
        }
        gdcm::SmartPointer<gdcm::SequenceOfItems> pp =
            item.GetDataElement(plane_pos).GetValueAsSQ();
        if (!pp || pp->GetNumberOfItems() < 1 ||
            get_nums(pp->GetItem(1).GetNestedDataSet(), 0x0020, 0x0032, pos + 3 * i, 3) != 3) {
            std::free(pos);
            return nullptr;
        }
    }
    return pos;
}

/* Up to @p n numbers of element (g, e) inside the functional-group macro
 * @p macro of an enhanced file: the Shared Functional Groups first, else the
 * first frame's Per-frame Functional Groups. */
int
group_nums(const gdcm::DataSet &ds, const gdcm::Tag &macro, uint16_t g, uint16_t e, double *out,
           int n) {
    static const gdcm::Tag groups[2] = {gdcm::Tag(0x5200, 0x9229), gdcm::Tag(0x5200, 0x9230)};
    for (const gdcm::Tag &gt : groups) {
        if (!ds.FindDataElement(gt))
            continue;
        gdcm::SmartPointer<gdcm::SequenceOfItems> sq = ds.GetDataElement(gt).GetValueAsSQ();
        if (!sq || sq->GetNumberOfItems() < 1)
            continue;
        const gdcm::DataSet &item = sq->GetItem(1).GetNestedDataSet();
        if (!item.FindDataElement(macro))
            continue;
        gdcm::SmartPointer<gdcm::SequenceOfItems> m = item.GetDataElement(macro).GetValueAsSQ();
        if (!m || m->GetNumberOfItems() < 1)
            continue;
        int k = get_nums(m->GetItem(1).GetNestedDataSet(), g, e, out, n);
        if (k > 0)
            return k;
    }
    return 0;
}

/* Image Orientation (Patient) of an enhanced file (shared functional groups). */
int
enhanced_orientation(const gdcm::File &file, double iop[6]) {
    std::vector<double> d = gdcm::ImageHelper::GetDirectionCosinesValue(file);
    if (d.size() != 6)
        return 0;
    for (int i = 0; i < 6; i++)
        iop[i] = d[(size_t)i];
    return 1;
}

/* JPEG, JPEG-LS and JPEG 2000 streams end with the marker FF D9 (EOI/EOC);
 * libjpeg decodes a stream cut short without an error, filling the rest, so
 * the last fragment's end is checked here. 1 also for other syntaxes. */
bool
jpeg_streams_end(const gdcm::Image &img) {
    const gdcm::TransferSyntax &ts = img.GetTransferSyntax();
    if (!ts.IsEncapsulated() || ts == gdcm::TransferSyntax::RLELossless)
        return true;
    const gdcm::SequenceOfFragments *sf = img.GetDataElement().GetSequenceOfFragments();
    if (!sf || sf->GetNumberOfFragments() == 0)
        return true;
    const gdcm::ByteValue *bv = sf->GetFragment(sf->GetNumberOfFragments() - 1).GetByteValue();
    if (!bv || !bv->GetPointer())
        return false;
    const unsigned char *p = reinterpret_cast<const unsigned char *>(bv->GetPointer());
    size_t n = bv->GetLength();
    while (n > 0 && p[n - 1] == 0) /* even-length padding */
        n--;
    /* some writers pad with a few more bytes (0xFF) after the marker */
    for (size_t k = 0; k < 8 && n >= 2 + k; k++)
        if (p[n - 2 - k] == 0xff && p[n - 1 - k] == 0xd9)
            return true;
    return false;
}

std::once_flag init_once;

/*
 * Walks the data elements of @p path and checks that no defined value
 * length runs past the end of the file. GDCM allocates an element's value
 * from its length before reading it, so a 1 KB file whose length field says
 * 900 MB made it allocate (and zero) 900 MB. Explicit and implicit VR, little
 * and big endian, nested sequences and items, encapsulated pixel data
 * (fragments skipped), UN values that are sequences (their elements in
 * implicit VR, as GDCM reads them: a UN of undefined length with an
 * implicit element claiming 2 GB inside made GDCM allocate it, found by
 * fuzzing); a deflated data set is not walked. Returns 0, or -1 with the
 * reason in @p err. Anything the walk cannot follow (an undefined length on
 * an element that is no sequence) ends it quietly: GDCM then decides.
 */
int
check_lengths(const char *path, char *err, size_t errlen) {
    std::FILE *fp = std::fopen(path, "rb");
    if (!fp)
        return 0; /* GDCM says why */
    std::fseek(fp, 0, SEEK_END);
    long fsz = std::ftell(fp);
    std::fseek(fp, 0, SEEK_SET);
    if (fsz <= 0) {
        std::fclose(fp);
        return 0;
    }
    const uint64_t size = (uint64_t)fsz;
    unsigned char b[12];
    uint64_t pos = 0;
    if (size >= 132 && std::fread(b, 1, 4, fp) == 4 && std::fseek(fp, 128, SEEK_SET) == 0 &&
        std::fread(b, 1, 4, fp) == 4 && !std::memcmp(b, "DICM", 4))
        pos = 132;
    int explicit_vr = 1, big = 0, in_meta = pos == 132, fragments = 0, rc = 0;
    char ts[72] = "";
    /* the sequences being walked: where each ends (UINT64_MAX: at its
     * sequence delimitation item) and the VR mode to go back to after it;
     * a UN sequence's elements are implicit VR little endian, as GDCM reads
     * them */
    struct open_seq {
        uint64_t end;
        int explicit_vr;
    };
    std::vector<open_seq> seqs;
    const size_t max_depth = 256;
    for (long count = 0; count < 4000000 && pos + 8 <= size; count++) {
        while (!seqs.empty() && seqs.back().end != UINT64_MAX && pos >= seqs.back().end) {
            explicit_vr = seqs.back().explicit_vr;
            seqs.pop_back();
        }
        if (std::fseek(fp, (long)pos, SEEK_SET) != 0 || std::fread(b, 1, 8, fp) != 8)
            break;
        auto u16 = [&](const unsigned char *q) {
            return big ? (unsigned)(q[0] << 8 | q[1]) : (unsigned)(q[1] << 8 | q[0]);
        };
        auto u32 = [&](const unsigned char *q) {
            return big ? (uint32_t)q[0] << 24 | (uint32_t)q[1] << 16 | (uint32_t)q[2] << 8 | q[3]
                       : (uint32_t)q[3] << 24 | (uint32_t)q[2] << 16 | (uint32_t)q[1] << 8 | q[0];
        };
        /* leaving the meta group: switch to the data set's transfer syntax */
        unsigned group = (unsigned)(b[1] << 8 | b[0]);
        if (in_meta && group != 0x0002) {
            in_meta = 0;
            if (!std::strcmp(ts, "1.2.840.10008.1.2"))
                explicit_vr = 0;
            else if (!std::strcmp(ts, "1.2.840.10008.1.2.2"))
                big = 1;
            else if (!std::strncmp(ts, "1.2.840.10008.1.2.1.99", 22))
                break; /* deflated: GDCM inflates it */
        }
        if (!in_meta && pos == 0) {
            /* no preamble: explicit when bytes 4-5 look like a VR */
            explicit_vr = std::isupper(b[4]) && std::isupper(b[5]);
        }
        group = u16(b);
        unsigned elem = u16(b + 2);
        uint64_t hdr = 8;
        uint32_t len;
        int sq = 0, un = 0;
        if (group == 0xfffe) {
            len = u32(b + 4); /* items and delimiters: no VR */
            if (elem == 0xe0dd) {
                if (fragments) {
                    fragments = 0;
                } else if (!seqs.empty() && seqs.back().end == UINT64_MAX) {
                    explicit_vr = seqs.back().explicit_vr;
                    seqs.pop_back();
                }
                len = 0;
            } else if (elem == 0xe00d) {
                len = 0;
            } else if (!fragments) {
                sq = 1; /* an item of a sequence: walk into it */
            }
        } else if (explicit_vr) {
            if (!std::isupper(b[4]) || !std::isupper(b[5])) {
                /* not a VR: GDCM falls back to reading it as implicit VR, so
                 * the four bytes are a length; check that one */
                len = u32(b + 4);
                if (in_meta && len == 0xffffffffu) {
                    /* GDCM asserts on it as on an explicit one */
                    std::snprintf(err, errlen,
                                  "element (%04x,%04x) of the file meta information has an "
                                  "undefined length",
                                  group, elem);
                    rc = -1;
                    break;
                }
                if (len != 0xffffffffu && pos + 8 + (uint64_t)len > size) {
                    std::snprintf(err, errlen,
                                  "element (%04x,%04x) claims %u bytes, but only %llu are left "
                                  "in the file",
                                  group, elem, len, (unsigned long long)(size - pos - 8));
                    rc = -1;
                    break;
                }
                /* and as a buggy explicit element with a 16-bit length,
                 * GDCM's other fallback: go on from there */
                pos += 8 + u16(b + 6);
                continue;
            }
            static const char *const long_vrs[] = {"OB", "OW", "OF", "SQ", "UT", "UN", "OD",
                                                   "OL", "UC", "UR", "OV", "SV", "UV"};
            int is_long = 0;
            for (const char *v : long_vrs)
                if (b[4] == (unsigned char)v[0] && b[5] == (unsigned char)v[1])
                    is_long = 1;
            static const char *const short_vrs[] = {"AE", "AS", "AT", "CS", "DA", "DS", "DT",
                                                    "FL", "FD", "IS", "LO", "LT", "PN", "SH",
                                                    "SL", "SS", "ST", "TM", "UI", "UL", "US"};
            int known = is_long;
            for (const char *v : short_vrs)
                if (b[4] == (unsigned char)v[0] && b[5] == (unsigned char)v[1])
                    known = 1;
            sq = b[4] == 'S' && b[5] == 'Q';
            /* a VR GDCM does not know is read as UN first (two reserved
             * bytes, a 32-bit length), its 16-bit form only after that
             * failed: the 32-bit length is what it allocates (a "CU" whose
             * value began "MONO" asked for 1.3 GB, found by fuzzing) */
            un = (b[4] == 'U' && b[5] == 'N') || !known;
            if (!known)
                is_long = 1;
            if (is_long) {
                if (pos + 12 > size || std::fread(b + 8, 1, 4, fp) != 4)
                    break;
                len = u32(b + 8);
                hdr = 12;
            } else {
                len = u16(b + 6);
            }
        } else {
            len = u32(b + 4);
        }
        if (len == 0xffffffffu && in_meta) {
            /* GDCM asserts (and aborts) on an undefined length in the meta group */
            std::snprintf(err, errlen,
                          "element (%04x,%04x) of the file meta information has an "
                          "undefined length",
                          group, elem);
            rc = -1;
            break;
        }
        if (len == 0xffffffffu) {
            if (group != 0xfffe) {
                if (group == 0x7fe0 && elem == 0x0010 && !sq && !un) {
                    fragments = 1; /* encapsulated pixel data: items are fragments */
                } else if (sq || un || !explicit_vr) {
                    /* a sequence (SQ, UN or implicit VR): its elements next,
                     * a UN's in implicit VR */
                    if (seqs.size() >= max_depth) {
                        std::snprintf(err, errlen, "sequences nested deeper than %zu", max_depth);
                        rc = -1;
                        break;
                    }
                    seqs.push_back({UINT64_MAX, explicit_vr});
                    if (un)
                        explicit_vr = 0;
                } else {
                    break; /* an undefined length GDCM will judge */
                }
            }
            pos += hdr;
            continue;
        }
        if (pos + hdr + len > size) {
            std::snprintf(err, errlen,
                          "element (%04x,%04x) claims %u bytes, but only %llu are left in the file",
                          group, elem, len, (unsigned long long)(size - pos - hdr));
            rc = -1;
            break;
        }
        if (in_meta && group == 0x0002 && elem == 0x0010 && len < sizeof ts) {
            if (std::fread(ts, 1, len, fp) != len)
                break;
            ts[len] = '\0';
            for (size_t i = len; i > 0 && (ts[i - 1] == ' ' || ts[i - 1] == '\0'); i--)
                ts[i - 1] = '\0';
        }
        if (un && len >= 8 && !big && seqs.size() < max_depth) {
            /* a UN value that starts with an item is a sequence to GDCM:
             * walk its implicit VR elements too */
            unsigned char it[4];
            if (std::fseek(fp, (long)(pos + hdr), SEEK_SET) == 0 && std::fread(it, 1, 4, fp) == 4 &&
                it[0] == 0xfe && it[1] == 0xff && it[2] == 0x00 && it[3] == 0xe0) {
                seqs.push_back({pos + hdr + len, explicit_vr});
                explicit_vr = 0;
                sq = 1;
            }
        }
        pos += hdr + (sq ? 0 : len); /* a defined-length sequence or item: its elements next */
    }
    std::fclose(fp);
    return rc;
}

} // namespace

extern "C" void
vv_dcm_init(void) {
    std::call_once(init_once, [] {
        try {
            gdcm::Global::GetInstance(); /* dictionaries */
            /* GDCM's warnings go to stderr; our errors carry the reasons */
            gdcm::Trace::SetWarning(false);
            gdcm::Trace::SetDebug(false);
            gdcm::Trace::SetError(false);
        } catch (...) {
        }
    });
}

extern "C" int
vv_dcm_prescan(const char *path, char *err, size_t errlen) {
    try {
        return check_lengths(path, err, errlen);
    } catch (const std::exception &e) {
        set_err(err, errlen, e.what());
    } catch (...) {
        set_err(err, errlen, "unreadable");
    }
    return -1;
}

extern "C" int
vv_dcm_read_header(const char *path, vv_dcm_file *f, char *err, size_t errlen) {
    char *keep = f->path;
    std::memset(f, 0, sizeof *f);
    f->path = keep;
    try {
        vv_dcm_init();
        if (check_lengths(path, err, errlen) != 0)
            return -1;
        gdcm::Reader r;
        r.SetFileName(path);
        if (!r.CanRead())
            return 0;
        std::set<gdcm::Tag> skip;
        if (!r.ReadUpToTag(gdcm::Tag(0x7fe0, 0x0010), skip)) {
            set_err(err, errlen, "cannot parse the DICOM header (truncated or corrupt)");
            return -1;
        }
        const gdcm::File &file = r.GetFile();
        const gdcm::DataSet &ds = file.GetDataSet();
        if (!ds.FindDataElement(gdcm::Tag(0x0028, 0x0010)) ||
            !ds.FindDataElement(gdcm::Tag(0x0028, 0x0011)))
            return 0; /* no image: a report, a structure set, a DICOMDIR */
        copy_str(f->series_uid, sizeof f->series_uid, get_str(ds, 0x0020, 0x000e));
        copy_str(f->series_desc, sizeof f->series_desc, get_str(ds, 0x0008, 0x103e));
        copy_str(f->modality, sizeof f->modality, get_str(ds, 0x0008, 0x0060));
        copy_str(f->study_desc, sizeof f->study_desc, get_str(ds, 0x0008, 0x1030));
        copy_str(f->study_date, sizeof f->study_date, get_str(ds, 0x0008, 0x0020));
        copy_str(f->patient_name, sizeof f->patient_name, get_str(ds, 0x0010, 0x0010));
        copy_str(f->patient_id, sizeof f->patient_id, get_str(ds, 0x0010, 0x0020));
        double num[6];
        f->series_number = get_nums(ds, 0x0020, 0x0011, num, 1) == 1 ? (int)num[0] : 0;
        f->instance_number = get_nums(ds, 0x0020, 0x0013, num, 1) == 1 ? (int)num[0] : 0;
        f->temporal_position = get_nums(ds, 0x0020, 0x0100, num, 1) == 1 ? (int)num[0] : 0;
        f->has_trigger = get_nums(ds, 0x0018, 0x1060, num, 1) == 1 && std::isfinite(num[0]);
        f->trigger_time = f->has_trigger ? num[0] : 0;

        std::vector<unsigned int> dims = gdcm::ImageHelper::GetDimensionsValue(file);
        gdcm::PixelFormat pf = gdcm::ImageHelper::GetPixelFormatValue(file);
        if (dims.size() < 2) {
            set_err(err, errlen, "no image dimensions");
            return -1;
        }
        f->cols = (int)std::min<unsigned int>(dims[0], 1u << 30);
        f->rows = (int)std::min<unsigned int>(dims[1], 1u << 30);
        f->frames =
            dims.size() > 2 && dims[2] > 0 ? (int)std::min<unsigned int>(dims[2], 1u << 30) : 1;
        f->samples = pf.GetSamplesPerPixel();
        f->bits_allocated = pf.GetBitsAllocated();
        /* PixelFormat::GetBitsStored asserts Bits Stored <= Bits Allocated
         * (an abort where assertions are on): check the whole format first */
        if (!pf.IsValid()) {
            std::snprintf(err, errlen,
                          "invalid pixel format (Bits Allocated %d, Bits Stored, High Bit or "
                          "Samples per Pixel out of range)",
                          f->bits_allocated);
            return -1;
        }
        f->bits_stored = pf.GetBitsStored();
        f->pixel_rep = pf.GetPixelRepresentation();
        f->planar = (int)gdcm::ImageHelper::GetPlanarConfigurationValue(file);
        const gdcm::TransferSyntax &ts = file.GetHeader().GetDataSetTransferSyntax();
        f->encapsulated =
            ts.IsEncapsulated() || ts == gdcm::TransferSyntax::DeflatedExplicitVRLittleEndian;
        f->native_le = ts == gdcm::TransferSyntax::ExplicitVRLittleEndian ||
                       ts == gdcm::TransferSyntax::ImplicitVRLittleEndian;
        f->pixel_end = f->encapsulated ? -1 : (long long)r.GetStreamCurrentPosition();

        f->has_ipp = get_nums(ds, 0x0020, 0x0032, f->ipp, 3) == 3;
        f->has_iop = get_nums(ds, 0x0020, 0x0037, f->iop, 6) == 6;
        f->has_spacing = get_nums(ds, 0x0028, 0x0030, f->pixel_spacing, 2) == 2;
        if (!f->has_spacing)
            f->has_spacing = get_nums(ds, 0x0018, 0x1164, f->pixel_spacing, 2) == 2;
        double rs[1], ri[1];
        int has_slope = get_nums(ds, 0x0028, 0x1053, rs, 1) == 1;
        int has_inter = get_nums(ds, 0x0028, 0x1052, ri, 1) == 1;
        f->slope = has_slope && rs[0] != 0 ? rs[0] : 1;
        f->intercept = has_inter ? ri[0] : 0;
        if (f->frames > 1) {
            /* enhanced objects keep geometry and rescale in functional groups */
            f->frame_ipp = frame_positions(ds, f->frames);
            if (!f->has_iop)
                f->has_iop =
                    group_nums(ds, gdcm::Tag(0x0020, 0x9116), 0x0020, 0x0037, f->iop, 6) == 6;
            if (!f->has_iop)
                f->has_iop = enhanced_orientation(file, f->iop);
            if (!f->has_spacing)
                f->has_spacing = group_nums(ds, gdcm::Tag(0x0028, 0x9110), 0x0028, 0x0030,
                                            f->pixel_spacing, 2) == 2;
            if (!has_slope && !has_inter) {
                has_slope = group_nums(ds, gdcm::Tag(0x0028, 0x9145), 0x0028, 0x1053, rs, 1);
                has_inter = group_nums(ds, gdcm::Tag(0x0028, 0x9145), 0x0028, 0x1052, ri, 1);
                if (has_slope || has_inter) {
                    f->slope = has_slope && rs[0] != 0 ? rs[0] : 1;
                    f->intercept = has_inter ? ri[0] : 0;
                }
            }
            std::vector<double> sp = gdcm::ImageHelper::GetSpacingValue(file);
            if (!f->has_spacing && sp.size() >= 2) {
                f->pixel_spacing[0] = sp[1];
                f->pixel_spacing[1] = sp[0];
                f->has_spacing = sp[0] > 0 && sp[1] > 0;
            }
            if (sp.size() >= 3)
                f->frame_spacing = sp[2];
            if (!f->has_ipp) {
                std::vector<double> o = gdcm::ImageHelper::GetOriginValue(file);
                if (o.size() == 3 && f->frame_ipp) {
                    for (int i = 0; i < 3; i++)
                        f->ipp[i] = o[(size_t)i];
                    f->has_ipp = 1;
                }
            }
            if (!has_slope && !has_inter) {
                std::vector<double> is = gdcm::ImageHelper::GetRescaleInterceptSlopeValue(file);
                if (is.size() == 2 && is[1] != 0) {
                    f->intercept = is[0];
                    f->slope = is[1];
                }
            }
        }
        return 1;
    } catch (const std::exception &e) {
        set_err(err, errlen, e.what());
    } catch (...) {
        set_err(err, errlen, "GDCM failed on the header");
    }
    std::free(f->frame_ipp);
    f->frame_ipp = nullptr;
    return -1;
}

extern "C" int
vv_dcm_read_pixels(const char *path, void *dst, size_t bytes, char *err, size_t errlen) {
    try {
        vv_dcm_init();
        if (check_lengths(path, err, errlen) != 0)
            return -1;
        gdcm::ImageReader r;
        r.SetFileName(path);
        if (!r.Read()) {
            set_err(err, errlen, "cannot read the pixel data (truncated or corrupt)");
            return -1;
        }
        const gdcm::Image &img = r.GetImage();
        unsigned long len = img.GetBufferLength();
        if (len != bytes) {
            char m[160];
            std::snprintf(m, sizeof m, "decoded pixel data is %lu bytes, the header says %zu", len,
                          bytes);
            set_err(err, errlen, m);
            return -1;
        }
        const gdcm::DataElement &pd = img.GetDataElement();
        const gdcm::ByteValue *bv = pd.GetByteValue();
        if (bv && img.GetTransferSyntax().IsEncapsulated() == false && bv->GetLength() < bytes) {
            char m[160];
            std::snprintf(m, sizeof m,
                          "pixel data holds %lu bytes, the image needs %zu (truncated)",
                          (unsigned long)bv->GetLength(), bytes);
            set_err(err, errlen, m);
            return -1;
        }
        if (!jpeg_streams_end(img)) {
            std::string ts = gdcm::TransferSyntax::GetTSString(img.GetTransferSyntax());
            std::string m = "corrupt compressed pixel data (" + ts +
                            "): the stream stops before its end-of-image marker (truncated)";
            set_err(err, errlen, m.c_str());
            return -1;
        }
        if (!img.GetBuffer(static_cast<char *>(dst))) {
            std::string ts = gdcm::TransferSyntax::GetTSString(img.GetTransferSyntax());
            std::string m = "cannot decode the pixel data (" + ts + "; corrupt or unsupported)";
            set_err(err, errlen, m.c_str());
            return -1;
        }
        return 0;
    } catch (const std::exception &e) {
        set_err(err, errlen, e.what());
    } catch (...) {
        set_err(err, errlen, "GDCM failed on the pixel data");
    }
    return -1;
}

extern "C" int
vv_dcm_dicomdir_files(const char *path, char ***files, int *n, char *err, size_t errlen) {
    *files = nullptr;
    *n = 0;
    try {
        vv_dcm_init();
        if (check_lengths(path, err, errlen) != 0)
            return -1;
        gdcm::Reader r;
        r.SetFileName(path);
        if (!r.CanRead() || !r.Read())
            return 0;
        gdcm::MediaStorage ms;
        ms.SetFromFile(r.GetFile());
        if (ms != gdcm::MediaStorage::MediaStorageDirectoryStorage)
            return 0;
        const gdcm::DataSet &ds = r.GetFile().GetDataSet();
        const gdcm::Tag records(0x0004, 0x1220);
        std::vector<std::string> out;
        std::string dir(path);
        size_t slash = dir.find_last_of('/');
        dir = slash == std::string::npos ? std::string(".") : dir.substr(0, slash);
        if (ds.FindDataElement(records)) {
            gdcm::SmartPointer<gdcm::SequenceOfItems> sq =
                ds.GetDataElement(records).GetValueAsSQ();
            for (size_t i = 1; sq && i <= sq->GetNumberOfItems(); i++) {
                const gdcm::DataSet &item = sq->GetItem(i).GetNestedDataSet();
                std::string ref = get_str(item, 0x0004, 0x1500);
                if (ref.empty())
                    continue;
                for (char &c : ref)
                    if (c == '\\')
                        c = '/';
                out.push_back(dir + "/" + ref);
            }
        }
        if (out.empty()) {
            set_err(err, errlen, "the DICOMDIR references no files");
            return -1;
        }
        char **v = static_cast<char **>(std::calloc(out.size(), sizeof(char *)));
        if (!v) {
            set_err(err, errlen, "out of memory");
            return -1;
        }
        for (size_t i = 0; i < out.size(); i++) {
            v[i] = strdup(out[i].c_str());
            if (!v[i]) {
                for (size_t j = 0; j < i; j++)
                    std::free(v[j]);
                std::free(v);
                set_err(err, errlen, "out of memory");
                return -1;
            }
        }
        *files = v;
        *n = (int)out.size();
        return 1;
    } catch (const std::exception &e) {
        set_err(err, errlen, e.what());
    } catch (...) {
        set_err(err, errlen, "GDCM failed on the DICOMDIR");
    }
    return -1;
}
