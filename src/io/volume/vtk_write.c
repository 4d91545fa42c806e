/*
 * The VTK writers (the legacy reader is vtk_legacy.c): volumes as legacy
 * STRUCTURED_POINTS (.vtk, BINARY: big-endian voxels after the header, as
 * the legacy format defines them) and as XML image data (.vti, the format
 * ParaView writes: one Piece, the voxels as one appended block, raw or
 * zlib-compressed in VTK's block layout), and meshes as XML PolyData
 * (.vtp: points, per-vertex normals and scalars, triangles).
 *
 * Geometry: VTK's world is the volume's own (no frame conversion).
 * STRUCTURED_POINTS holds origin and spacing only: a volume whose direction
 * matrix is not the identity is written axis-aligned, with a warning (the
 * record's fits, in vtk_legacy.c). ImageData holds the direction (its Direction attribute,
 * row-major, read by VTK >= 9). Numbers are written with 17 significant digits, so doubles come
 * back exactly.
 *
 * The XML files are written by hand: the header is a few fixed elements, and
 * the appended block is VTK's binary layout (a UInt64 byte count, or the
 * compressed-block table: number of blocks, block size, last block size,
 * then each compressed size), which no XML library writes.
 *
 * Thread-safety: reentrant. Every write is atomic (vv_atomic_file).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "core/internal.h"
#include "io/io_internal.h"
#include "io/volume/vti.h"
#include "io/write_check.h"
#include "volvis/io.h"
#include "volvis/mesh.h"
#include "volvis/sys/format.h"

/* Bytes of voxels byte-swapped per write of the legacy writer, and
 * uncompressed bytes per block of the .vti writer (VTK's readers take any). */
#define VTK_CHUNK ((size_t)1 << 20)

static const char *
legacy_type(vv_voxel_type t) {
    static const char *const names[] = {"unsigned_char", "char", "unsigned_short", "short",
                                        "unsigned_int",  "int",  "float",          "double"};
    return (int)t >= 0 && (int)t < 8 ? names[t] : NULL;
}

static const char *
xml_type(vv_voxel_type t) {
    static const char *const names[] = {"UInt8",  "Int8",  "UInt16",  "Int16",
                                        "UInt32", "Int32", "Float32", "Float64"};
    return (int)t >= 0 && (int)t < 8 ? names[t] : NULL;
}

static vv_status
check_volume(const vv_volume *v) {
    vv_status s = io_write_check_voxels(v, v->data != NULL, legacy_type(v->type) != NULL);
    return s != VV_OK ? s : io_write_check_geometry(v, IO_WRITE_ANY_SPACING);
}

static vv_status
put(FILE *fp, const void *p, size_t n) {
    if (n && fwrite(p, 1, n, fp) != n)
        return vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno ? errno : EIO));
    return VV_OK;
}

static vv_status
finish(vv_atomic_file *af, vv_status s, const char *prefix, const char *path) {
    if (s == VV_OK)
        s = vv_atomic_file_commit(af);
    else
        vv_atomic_file_abort(af);
    if (s != VV_OK)
        return vv_error_prefix(s, "%s: %s", prefix, vv_path_basename(path));
    return VV_OK;
}

/* ---- legacy STRUCTURED_POINTS ------------------------------------------ */

vv_status
vv_vtk_write(const vv_volume *v, const char *path) {
    if (!v || !path)
        return vv_error_set(VV_ERR_INVALID, "vtk: NULL argument");
    vv_status s = check_volume(v);
    if (s != VV_OK)
        return vv_error_prefix(s, "vtk: %s", vv_path_basename(path));
    vv_atomic_file af;
    if ((s = vv_atomic_file_open(&af, path)) != VV_OK)
        return vv_error_prefix(s, "vtk: %s", vv_path_basename(path));
    uint64_t n = vv_volume_voxel_count(v);
    size_t size = vv_voxel_type_size(v->type);
    if (fprintf(af.fp,
                "# vtk DataFile Version 3.0\nVolVis volume\nBINARY\nDATASET STRUCTURED_POINTS\n"
                "DIMENSIONS %d %d %d\nORIGIN %.17g %.17g %.17g\nSPACING %.17g %.17g %.17g\n"
                "POINT_DATA %llu\nSCALARS scalars %s 1\nLOOKUP_TABLE default\n",
                v->dims[0], v->dims[1], v->dims[2], v->origin[0], v->origin[1], v->origin[2],
                v->spacing[0], v->spacing[1], v->spacing[2], (unsigned long long)n,
                legacy_type(v->type)) < 0)
        s = vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno));
    /* big-endian: swapped through a bounded buffer (one byte: as it is) */
    unsigned char *buf = size > 1 ? malloc(VTK_CHUNK) : NULL;
    if (s == VV_OK && size > 1 && !buf)
        s = vv_error_set(VV_ERR_NOMEM, "out of memory");
    const unsigned char *src = v->data;
    uint64_t total = n * size;
    for (uint64_t at = 0; s == VV_OK && at < total;) {
        size_t len = (size_t)(total - at < VTK_CHUNK ? total - at : VTK_CHUNK);
        if (size == 1) {
            s = put(af.fp, src + at, len);
        } else {
            for (size_t i = 0; i < len; i += size)
                for (size_t b = 0; b < size; b++)
                    buf[i + b] = src[at + i + size - 1 - b];
            s = put(af.fp, buf, len);
        }
        at += len;
    }
    if (s == VV_OK && fputc('\n', af.fp) == EOF)
        s = vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno));
    free(buf);
    return finish(&af, s, "vtk", path);
}

/* ---- XML: the appended block -------------------------------------------- */

/* Bytes the appended block of @p n raw bytes takes (header included), raw. */
static uint64_t
raw_block_bytes(uint64_t n) {
    return 8 + n;
}

/* Writes @p n bytes at @p p as an appended block: raw (a UInt64 count, then
 * the bytes) or zlib-compressed in VTK's layout (a table of UInt64 block
 * sizes, patched once the blocks are written, then the blocks). *@p written
 * gets the block's size. The file must be seekable (it is: vv_atomic_file). */
static vv_status
put_block(FILE *fp, const void *p, uint64_t n, int compress, uint64_t *written) {
    vv_status s = VV_OK;
    if (!compress) {
        uint64_t c = n;
        if ((s = put(fp, &c, 8)) == VV_OK)
            s = put(fp, p, (size_t)n);
        *written = raw_block_bytes(n);
        return s;
    }
    uint64_t nb = n ? (n + VTK_CHUNK - 1) / VTK_CHUNK : 0;
    uint64_t *table = calloc((size_t)(3 + nb), sizeof *table);
    unsigned char *zbuf = malloc(compressBound(VTK_CHUNK));
    if (!table || !zbuf) {
        free(table);
        free(zbuf);
        return vv_error_set(VV_ERR_NOMEM, "out of memory");
    }
    table[0] = nb;
    table[1] = VTK_CHUNK;
    table[2] = nb ? n - (nb - 1) * VTK_CHUNK : 0;
    off_t at = ftello(fp);
    if (at < 0)
        s = vv_error_set(VV_ERR_IO, "cannot tell the position: %s", strerror(errno));
    if (s == VV_OK)
        s = put(fp, table, (size_t)(3 + nb) * 8);
    uint64_t total = (3 + nb) * 8;
    const unsigned char *src = p;
    for (uint64_t b = 0; s == VV_OK && b < nb; b++) {
        size_t len = (size_t)(b + 1 < nb ? VTK_CHUNK : table[2]);
        uLongf zlen = compressBound(VTK_CHUNK);
        if (compress2(zbuf, &zlen, src + b * VTK_CHUNK, (uLong)len, 1) != Z_OK)
            s = vv_error_set(VV_ERR_NOMEM, "zlib failed to compress a block");
        else
            s = put(fp, zbuf, zlen);
        table[3 + b] = zlen;
        total += zlen;
    }
    off_t end = s == VV_OK ? ftello(fp) : -1;
    if (s == VV_OK && (end < 0 || fseeko(fp, at, SEEK_SET) != 0))
        s = vv_error_set(VV_ERR_IO, "cannot seek: %s", strerror(errno));
    if (s == VV_OK)
        s = put(fp, table, (size_t)(3 + nb) * 8);
    if (s == VV_OK && fseeko(fp, end, SEEK_SET) != 0)
        s = vv_error_set(VV_ERR_IO, "cannot seek: %s", strerror(errno));
    free(table);
    free(zbuf);
    *written = total;
    return s;
}

static int
host_little_endian(void) {
    const uint16_t one = 1;
    return *(const unsigned char *)&one == 1;
}

static const char *
xml_head(int compress) {
    return compress ? "<?xml version=\"1.0\"?>\n<VTKFile type=\"%s\" version=\"1.0\" "
                      "byte_order=\"%s\" header_type=\"UInt64\" "
                      "compressor=\"vtkZLibDataCompressor\">\n"
                    : "<?xml version=\"1.0\"?>\n<VTKFile type=\"%s\" version=\"1.0\" "
                      "byte_order=\"%s\" header_type=\"UInt64\">\n";
}

/* ---- XML image data (.vti) ------------------------------------------------ */

vv_status
vv_vti_write(const vv_volume *v, const char *path, int compress) {
    if (!v || !path)
        return vv_error_set(VV_ERR_INVALID, "vti: NULL argument");
    vv_status s = check_volume(v);
    if (s != VV_OK)
        return vv_error_prefix(s, "vti: %s", vv_path_basename(path));
    vv_atomic_file af;
    if ((s = vv_atomic_file_open(&af, path)) != VV_OK)
        return vv_error_prefix(s, "vti: %s", vv_path_basename(path));
    const char *order = host_little_endian() ? "LittleEndian" : "BigEndian";
    const double *d = v->direction;
    FILE *fp = af.fp;
    int e0 = v->dims[0] - 1, e1 = v->dims[1] - 1, e2 = v->dims[2] - 1;
    if (fprintf(fp, xml_head(compress), "ImageData", order) < 0 ||
        fprintf(fp,
                "  <ImageData WholeExtent=\"0 %d 0 %d 0 %d\" Origin=\"%.17g %.17g %.17g\" "
                "Spacing=\"%.17g %.17g %.17g\" Direction=\"%.17g %.17g %.17g %.17g %.17g %.17g "
                "%.17g %.17g %.17g\">\n"
                "    <Piece Extent=\"0 %d 0 %d 0 %d\">\n"
                "      <PointData Scalars=\"scalars\">\n"
                "        <DataArray type=\"%s\" Name=\"scalars\" format=\"appended\" "
                "RangeMin=\"%.17g\" RangeMax=\"%.17g\" offset=\"0\"/>\n"
                "      </PointData>\n      <CellData>\n      </CellData>\n"
                "    </Piece>\n  </ImageData>\n  <AppendedData encoding=\"raw\">\n   _",
                e0, e1, e2, v->origin[0], v->origin[1], v->origin[2], v->spacing[0], v->spacing[1],
                v->spacing[2], d[0], d[1], d[2], d[3], d[4], d[5], d[6], d[7], d[8], e0, e1, e2,
                xml_type(v->type), v->range[0], v->range[1]) < 0)
        s = vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno));
    uint64_t bytes = vv_volume_voxel_count(v) * vv_voxel_type_size(v->type), w = 0;
    if (s == VV_OK)
        s = put_block(fp, v->data, bytes, compress, &w);
    if (s == VV_OK && fputs("\n  </AppendedData>\n</VTKFile>\n", fp) == EOF)
        s = vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno));
    return finish(&af, s, "vti", path);
}

/* ---- XML PolyData (.vtp) -------------------------------------------------- */

vv_status
vv_vtp_write(const vv_mesh *m, const char *path, const char *scalar_name) {
    if (!m || !path)
        return vv_error_set(VV_ERR_INVALID, "vtp: NULL argument");
    if (!m->n_vertices || !m->n_triangles)
        return vv_error_set(VV_ERR_INVALID, "vtp: %s: the mesh is empty", vv_path_basename(path));
    if (!scalar_name || !*scalar_name)
        scalar_name = "scalars";
    for (const char *c = scalar_name; *c; c++)
        if (*c == '"' || *c == '<' || *c == '&' || (unsigned char)*c < 32)
            return vv_error_set(VV_ERR_INVALID, "vtp: the field name \"%s\" is not plain text",
                                scalar_name);
    size_t nv = m->n_vertices, nt = m->n_triangles;
    int64_t *conn = malloc(nt * 3 * sizeof *conn), *offs = malloc(nt * sizeof *offs);
    if (!conn || !offs) {
        free(conn);
        free(offs);
        return vv_error_set(VV_ERR_NOMEM, "vtp: out of memory");
    }
    for (size_t i = 0; i < nt * 3; i++)
        conn[i] = (int64_t)m->triangles[i];
    for (size_t i = 0; i < nt; i++)
        offs[i] = (int64_t)(3 * (i + 1));
    vv_atomic_file af;
    vv_status s = vv_atomic_file_open(&af, path);
    if (s != VV_OK) {
        free(conn);
        free(offs);
        return vv_error_prefix(s, "vtp: %s", vv_path_basename(path));
    }
    FILE *fp = af.fp;
    /* the appended blocks in order: points, normals, scalars, connectivity,
     * offsets; each raw (a count, then the bytes) */
    uint64_t o_pts = 0, o_nrm = o_pts + raw_block_bytes(nv * 12);
    uint64_t o_sca = o_nrm + (m->normals ? raw_block_bytes(nv * 12) : 0);
    uint64_t o_con = o_sca + (m->scalars ? raw_block_bytes(nv * 4) : 0);
    uint64_t o_off = o_con + raw_block_bytes(nt * 24);
    char pd[512] = "";
    if (m->normals)
        snprintf(pd, sizeof pd,
                 "        <DataArray type=\"Float32\" Name=\"Normals\" NumberOfComponents=\"3\" "
                 "format=\"appended\" offset=\"%llu\"/>\n",
                 (unsigned long long)o_nrm);
    if (m->scalars) {
        size_t l = strlen(pd);
        snprintf(pd + l, sizeof pd - l,
                 "        <DataArray type=\"Float32\" Name=\"%s\" format=\"appended\" "
                 "offset=\"%llu\"/>\n",
                 scalar_name, (unsigned long long)o_sca);
    }
    if (fprintf(fp, xml_head(0), "PolyData", host_little_endian() ? "LittleEndian" : "BigEndian") <
            0 ||
        fprintf(fp,
                "  <PolyData>\n    <Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"0\" "
                "NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"%zu\">\n"
                "      <PointData%s%s%s%s%s>\n%s      </PointData>\n"
                "      <Points>\n        <DataArray type=\"Float32\" Name=\"Points\" "
                "NumberOfComponents=\"3\" format=\"appended\" offset=\"%llu\"/>\n      </Points>\n"
                "      <Polys>\n        <DataArray type=\"Int64\" Name=\"connectivity\" "
                "format=\"appended\" offset=\"%llu\"/>\n        <DataArray type=\"Int64\" "
                "Name=\"offsets\" format=\"appended\" offset=\"%llu\"/>\n      </Polys>\n"
                "    </Piece>\n  </PolyData>\n  <AppendedData encoding=\"raw\">\n   _",
                nv, nt, m->normals ? " Normals=\"Normals\"" : "", m->scalars ? " Scalars=\"" : "",
                m->scalars ? scalar_name : "", m->scalars ? "\"" : "", "", pd,
                (unsigned long long)o_pts, (unsigned long long)o_con,
                (unsigned long long)o_off) < 0)
        s = vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno));
    uint64_t w;
    if (s == VV_OK)
        s = put_block(fp, m->positions, nv * 12, 0, &w);
    if (s == VV_OK && m->normals)
        s = put_block(fp, m->normals, nv * 12, 0, &w);
    if (s == VV_OK && m->scalars)
        s = put_block(fp, m->scalars, nv * 4, 0, &w);
    if (s == VV_OK)
        s = put_block(fp, conn, nt * 24, 0, &w);
    if (s == VV_OK)
        s = put_block(fp, offs, nt * 8, 0, &w);
    if (s == VV_OK && fputs("\n  </AppendedData>\n</VTKFile>\n", fp) == EOF)
        s = vv_error_set(VV_ERR_IO, "write failed: %s", strerror(errno));
    free(conn);
    free(offs);
    return finish(&af, s, "vtp", path);
}

/* ---- the format records ----------------------------------------------------- */

static vv_status
vti_write_record(const vv_volume *v, const char *path, const vv_save_options *opt) {
    return vv_vti_write(v, path, opt->compress != 0);
}

static const char *const vti_extensions[] = {"vti", NULL};

const vv_format_record vv_format_vti = {
    .version = VV_FORMAT_RECORD_VERSION,
    .name = "vti",
    .title = "VTK XML image data",
    .extensions = vti_extensions,
    .doc = "VTK XML image data (ParaView's .vti) through libxml2: reads inline or appended, "
           "base64 or raw, zlib, components as channels; writes origin, spacing and direction, "
           "every voxel type, one appended block, zlib-compressed unless --no-compress",
    .flags = VV_FORMAT_FLAG_THIRD_PARTY,
    .looks_like = vv_vti_looks_like,
    .read = vv_vti_read,
    .write = vti_write_record,
};
