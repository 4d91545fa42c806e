/*
 * libFuzzer harness: BigDataViewer datasets (src/io/store/bdv_xml.c: the SpimData
 * XML, its setups, time points, registrations and the HDF5 file it names)
 * and the HDF5 pyramids beneath them (src/io/store/hdf5_pyramid.c: BigDataViewer's
 * t<T>/s<S>/<level>/cells, s<S>/resolutions and s<S>/subdivisions; Imaris's
 * DataSet/ResolutionLevel N/TimePoint T/Channel C/Data and DataSetInfo/Image
 * attributes; the companion XML's voxel size).
 *
 * Structure-aware: the HDF5 file is not the input's bytes (HDF5's own
 * binary format is libhdf5's to parse) but is built here with the HDF5 C
 * API from a description, so the fuzzer explores what OUR reader makes of
 * the file's groups, datasets, shapes, types, chunks and attributes.
 *
 * The input: the XML text, a line "--H5--", then the description. The XML
 * is written as in.xml (the dataset XML, and in.h5's companion XML) unless
 * it is empty (an input starting with "--H5--\n": the HDF5 pyramid alone,
 * without a companion). The description, one command a line, fields
 * separated by spaces ("..." quotes a field holding spaces; '#' starts a
 * comment line; at most 64 commands):
 *
 *     o LEVEL CHANNEL TIME          the level, channel and step asked (0 -1 -1)
 *     g PATH                        a group (its parents made)
 *     d PATH TYPE DIMS CHUNKS V...  a dataset: DIMS "z,y,x" (1 to 5 sizes),
 *                                   CHUNKS "-" (contiguous) or sizes,
 *                                   "+z" after them for deflate; V... its
 *                                   values, repeated (none: never written)
 *     a PATH NAME TYPE V...         an attribute of object PATH ("/" the
 *                                   root): a numeric TYPE with V... (1-D;
 *                                   none: a scalar 0), or "chars" (Imaris: V
 *                                   as an array of one-byte strings), "str"
 *                                   (one fixed-length string), "vstr" (a
 *                                   variable-length one)
 *     l PATH TARGET                 a soft link (may dangle)
 *     x PATH FILE OBJECT            an external link into FILE of the folder
 *
 * TYPE: u8 i8 u16 i16 u32 i32 u64 i64 f32 f64 (native order; a leading '>'
 * for big-endian), s4 (a 4-byte string: no voxel type). A command that HDF5
 * refuses (a chunk larger than the dataset, a clashing name) is skipped.
 * Datasets of over 2^18 elements are never written (chunks never written
 * read as the fill value, at no cost), so a huge claimed shape costs
 * nothing to build.
 *
 * Read as the library reads them (VOLVIS_SANDBOX=0: in this process): the
 * XML (when there is one) and the HDF5 file, each by vv_open whole and out
 * of core (their formats named: no other row's reader is reached), a small box of every level and
 * the coarsest level's proxy; in a cache of the harness's own.
 */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <hdf5.h>

#include "fuzz_util.h"
#include "volvis/volvis.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* As fuzz_zarr.c: a small budget keeps whole reads cheap; every check runs. */
#define BDV_FUZZ_BUDGET ((uint64_t)8 << 20)
#define BDV_MAX_COMMANDS 64
#define BDV_MAX_TOKENS 80
#define BDV_MAX_WRITE ((uint64_t)1 << 18)

/* Splits @p line (modified) into at most BDV_MAX_TOKENS fields. */
static int
tokenize(char *line, char **tok) {
    int n = 0;
    char *p = line;
    while (n < BDV_MAX_TOKENS) {
        while (*p == ' ' || *p == '\t' || *p == '\r')
            p++;
        if (!*p)
            break;
        if (*p == '"') {
            tok[n++] = ++p;
            while (*p && *p != '"')
                p++;
        } else {
            tok[n++] = p;
            while (*p && *p != ' ' && *p != '\t' && *p != '\r')
                p++;
        }
        if (!*p)
            break;
        *p++ = '\0';
    }
    return n;
}

/* The file type of @p name; -1 when none (not to be closed). */
static hid_t
file_type(const char *name) {
    static const struct {
        const char *k;
        hid_t *le, *be;
    } map[] = {{"u8", &H5T_STD_U8LE_g, &H5T_STD_U8BE_g},
               {"i8", &H5T_STD_I8LE_g, &H5T_STD_I8BE_g},
               {"u16", &H5T_STD_U16LE_g, &H5T_STD_U16BE_g},
               {"i16", &H5T_STD_I16LE_g, &H5T_STD_I16BE_g},
               {"u32", &H5T_STD_U32LE_g, &H5T_STD_U32BE_g},
               {"i32", &H5T_STD_I32LE_g, &H5T_STD_I32BE_g},
               {"u64", &H5T_STD_U64LE_g, &H5T_STD_U64BE_g},
               {"i64", &H5T_STD_I64LE_g, &H5T_STD_I64BE_g},
               {"f32", &H5T_IEEE_F32LE_g, &H5T_IEEE_F32BE_g},
               {"f64", &H5T_IEEE_F64LE_g, &H5T_IEEE_F64BE_g}};
    const int be = name[0] == '>';
    name += be;
    for (size_t i = 0; i < sizeof map / sizeof map[0]; i++)
        if (!strcmp(name, map[i].k))
            return be ? *map[i].be : *map[i].le;
    return -1;
}

/* Sizes "a,b,c" into @p out (at most 5); their count, 0 when not sizes. */
static int
parse_sizes(const char *t, hsize_t *out) {
    int n = 0;
    while (*t && n < 5) {
        char *end;
        errno = 0;
        const unsigned long long x = strtoull(t, &end, 10);
        if (end == t || errno || x > ((unsigned long long)1 << 40))
            return 0;
        out[n++] = (hsize_t)x;
        t = end;
        if (*t == ',')
            t++;
        else
            break;
    }
    return n;
}

/* A dataset: d PATH TYPE DIMS CHUNKS V... */
static void
make_dataset(hid_t fid, hid_t lcpl, char **tok, int nt) {
    if (nt < 5)
        return;
    hsize_t dims[5], ch[5];
    const int rank = parse_sizes(tok[3], dims);
    const int is_str = !strcmp(tok[2], "s4");
    hid_t ft = is_str ? H5Tcopy(H5T_C_S1) : file_type(tok[2]);
    if (rank < 1 || ft < 0) {
        if (is_str && ft >= 0)
            H5Tclose(ft);
        return;
    }
    if (is_str)
        H5Tset_size(ft, 4);
    hid_t sp = H5Screate_simple(rank, dims, NULL);
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    if (strcmp(tok[4], "-") != 0 && parse_sizes(tok[4], ch) == rank) {
        H5Pset_chunk(dcpl, rank, ch);
        if (strstr(tok[4], "+z"))
            H5Pset_deflate(dcpl, 1);
    }
    hid_t d = sp >= 0 ? H5Dcreate2(fid, tok[1], ft, sp, lcpl, dcpl, H5P_DEFAULT) : -1;
    uint64_t n = 1;
    for (int k = 0; k < rank && n <= BDV_MAX_WRITE; k++)
        n = dims[k] > BDV_MAX_WRITE ? BDV_MAX_WRITE + 1 : n * dims[k];
    if (d >= 0 && nt > 5 && n >= 1 && n <= BDV_MAX_WRITE) {
        if (is_str) {
            char *buf = malloc(n * 4);
            if (buf) {
                for (uint64_t i = 0; i < n; i++)
                    strncpy(buf + 4 * i, tok[5 + i % (uint64_t)(nt - 5)], 4);
                H5Dwrite(d, ft, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
                free(buf);
            }
        } else {
            double *buf = malloc(n * sizeof *buf);
            if (buf) {
                for (uint64_t i = 0; i < n; i++)
                    buf[i] = strtod(tok[5 + i % (uint64_t)(nt - 5)], NULL);
                H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf);
                free(buf);
            }
        }
    }
    if (d >= 0)
        H5Dclose(d);
    H5Pclose(dcpl);
    if (sp >= 0)
        H5Sclose(sp);
    if (is_str)
        H5Tclose(ft);
}

/* An attribute: a PATH NAME TYPE V... */
static void
make_attribute(hid_t fid, char **tok, int nt) {
    if (nt < 4)
        return;
    hid_t obj = H5Oopen(fid, tok[1], H5P_DEFAULT);
    if (obj < 0)
        return;
    const char *kind = tok[3];
    hid_t ft = -1, sp = -1, a = -1;
    const char *text = nt > 4 ? tok[4] : "";
    const size_t len = strlen(text);
    if (!strcmp(kind, "chars")) { /* Imaris: one one-byte string a character */
        const hsize_t n = len ? len : 1;
        ft = H5Tcopy(H5T_C_S1);
        H5Tset_size(ft, 1);
        sp = H5Screate_simple(1, &n, NULL);
        a = H5Acreate2(obj, tok[2], ft, sp, H5P_DEFAULT, H5P_DEFAULT);
        if (a >= 0)
            H5Awrite(a, ft, len ? text : "");
    } else if (!strcmp(kind, "str") || !strcmp(kind, "vstr")) {
        ft = H5Tcopy(H5T_C_S1);
        const int var = kind[0] == 'v';
        H5Tset_size(ft, var ? H5T_VARIABLE : (len ? len : 1));
        sp = H5Screate(H5S_SCALAR);
        a = H5Acreate2(obj, tok[2], ft, sp, H5P_DEFAULT, H5P_DEFAULT);
        if (a >= 0)
            H5Awrite(a, ft, var ? (const void *)&text : (const void *)text);
    } else if (file_type(kind) >= 0) {
        double v[BDV_MAX_TOKENS];
        const hsize_t n = (hsize_t)(nt - 4);
        for (int i = 4; i < nt; i++)
            v[i - 4] = strtod(tok[i], NULL);
        v[0] = n ? v[0] : 0;
        sp = n ? H5Screate_simple(1, &n, NULL) : H5Screate(H5S_SCALAR);
        a = H5Acreate2(obj, tok[2], file_type(kind), sp, H5P_DEFAULT, H5P_DEFAULT);
        if (a >= 0)
            H5Awrite(a, H5T_NATIVE_DOUBLE, v);
    }
    if (a >= 0)
        H5Aclose(a);
    if (sp >= 0)
        H5Sclose(sp);
    if (ft >= 0)
        H5Tclose(ft);
    H5Oclose(obj);
}

/* A flat file name of the harness's folder (an external link's target). */
static int
flat_name(const char *s) {
    if (!*s || !strcmp(s, ".") || !strcmp(s, ".."))
        return 0;
    for (; *s; s++)
        if (!((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') || (*s >= '0' && *s <= '9') ||
              *s == '.' || *s == '_' || *s == '-'))
            return 0;
    return 1;
}

/* Builds @p path from the description; the asked level, channel, step into ask[3]. */
static void
build_h5(const char *path, const uint8_t *desc, size_t n, int ask[3]) {
    hid_t fid = H5Fcreate(path, H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (fid < 0) {
        fprintf(stderr, "fuzz: cannot create %s\n", path);
        abort(); /* the machine, not the input */
    }
    hid_t lcpl = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(lcpl, 1);
    char *text = malloc(n + 1);
    if (!text)
        abort();
    memcpy(text, desc, n);
    text[n] = '\0';
    int commands = 0;
    for (char *save = NULL, *line = strtok_r(text, "\n", &save);
         line && commands < BDV_MAX_COMMANDS; line = strtok_r(NULL, "\n", &save)) {
        char *tok[BDV_MAX_TOKENS];
        const int nt = tokenize(line, tok);
        if (nt < 2 || tok[0][0] == '#' || tok[0][1])
            continue;
        commands++;
        switch (tok[0][0]) {
        case 'o':
            for (int k = 0; k < 3 && k + 1 < nt; k++) {
                const long v = strtol(tok[k + 1], NULL, 10);
                ask[k] = v >= -1 && v <= 20 ? (int)v : ask[k];
            }
            break;
        case 'g': {
            hid_t g = H5Gcreate2(fid, tok[1], lcpl, H5P_DEFAULT, H5P_DEFAULT);
            if (g >= 0)
                H5Gclose(g);
            break;
        }
        case 'd':
            make_dataset(fid, lcpl, tok, nt);
            break;
        case 'a':
            make_attribute(fid, tok, nt);
            break;
        case 'l':
            if (nt >= 3)
                H5Lcreate_soft(tok[2], fid, tok[1], lcpl, H5P_DEFAULT);
            break;
        case 'x':
            if (nt >= 4 && flat_name(tok[2]))
                H5Lcreate_external(tok[2], tok[3], fid, tok[1], lcpl, H5P_DEFAULT);
            break;
        default:
            break;
        }
    }
    free(text);
    H5Pclose(lcpl);
    if (H5Fclose(fid) < 0) {
        fprintf(stderr, "fuzz: cannot close %s\n", path);
        abort();
    }
}

static void
open_file(const char *path, vv_format format, vv_open_mode mode, const int ask[3],
          vv_cache *cache) {
    vv_open_options oo;
    vv_open_options_init(&oo);
    oo.mode = mode;
    oo.load.format = format; /* named: no other row's (third-party) reader is reached */
    oo.load.level = ask[0];
    oo.load.channel = ask[1];
    oo.load.time = ask[2];
    oo.cache = cache;
    vv_opened o;
    memset(&o, 0, sizeof o);
    const vv_status st = vv_open(&o, path, &oo);
    fuzz_check_status(st);
    if (st != VV_OK)
        return;
    if (o.kind != VV_DATA_VOLUME || !o.source)
        __builtin_trap(); /* a pyramid holds a volume */
    if (!memchr(o.info.channel_name, '\0', sizeof o.info.channel_name))
        __builtin_trap();
    fuzz_read_source(o.source);
    vv_opened_clear(&o);
}

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
    static vv_cache *cache; /* one budget for every input, as a process has */
    if (!cache) {
        vv_memory_budget_set(BDV_FUZZ_BUDGET);
        H5Eset_auto2(H5E_DEFAULT, NULL, NULL); /* the commands HDF5 refuses are skipped */
        if (vv_cache_new(&cache, BDV_FUZZ_BUDGET) != VV_OK)
            __builtin_trap();
    }
    static const char sep[] = "--H5--\n";
    const uint8_t *xml, *desc;
    size_t nx, nd;
    if (size >= sizeof sep - 1 && !memcmp(data, sep, sizeof sep - 1)) {
        xml = data; /* the pyramid alone */
        nx = 0;
        desc = data + sizeof sep - 1;
        nd = size - (sizeof sep - 1);
    } else {
        fuzz_split(data, size, "\n--H5--\n", &xml, &nx, &desc, &nd);
    }
    int ask[3] = {0, -1, -1};
    char h5[512], xp[512];
    snprintf(h5, sizeof h5, "%s/in.h5", fuzz_dir());
    snprintf(xp, sizeof xp, "%s/in.xml", fuzz_dir());
    unlink(xp);
    build_h5(h5, desc, nd, ask);
    if (nx > 0) {
        fuzz_write("in.xml", xml, nx);
        open_file(xp, VV_FORMAT_BDV_XML, VV_OPEN_WHOLE, ask, cache);
        open_file(xp, VV_FORMAT_BDV_XML, VV_OPEN_OUT_OF_CORE, ask, cache);
    }
    open_file(h5, VV_FORMAT_HDF5, VV_OPEN_WHOLE, ask, cache);
    open_file(h5, VV_FORMAT_HDF5, VV_OPEN_OUT_OF_CORE, ask, cache);
    return 0;
}
