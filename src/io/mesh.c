/*
 * Mesh files through Assimp: every format Assimp reads (OBJ, PLY, STL, OFF,
 * glTF, ...) into a vv_mesh, and binary PLY, OBJ and binary STL written by
 * Assimp's exporters (see include/volvis/mesh.h).
 */
#include <assimp/cexport.h>
#include <assimp/cimport.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "core/internal.h"
#include "volvis/mesh.h"

/* Mesh files larger than this are refused before Assimp reads them. */
#define MESH_MAX_FILE_BYTES ((uint64_t)8 << 30)

vv_status
vv_mesh_load(vv_mesh **out, const char *path) {
    if (!out || !path)
        return vv_error_set(VV_ERR_INVALID, "mesh: NULL argument");
    *out = NULL;
    const char *name = vv_path_basename(path);
    FILE *fp = NULL;
    uint64_t size = 0;
    vv_status s = vv_open_regular(path, &fp, &size);
    if (s != VV_OK)
        return vv_error_prefix(s, "mesh: %s", name);
    fclose(fp);
    if (size > MESH_MAX_FILE_BYTES)
        return vv_error_set(VV_ERR_LIMIT, "mesh: %s: %llu bytes (at most %llu)", name,
                            (unsigned long long)size, (unsigned long long)MESH_MAX_FILE_BYTES);
    if (size == 0)
        return vv_error_set(VV_ERR_FORMAT, "mesh: %s: empty file", name);

    /* Drop every attribute but positions before joining vertices, so facet
     * normals (STL) or texture seams do not split a closed surface; normals
     * are recomputed from the shared vertices. */
    struct aiPropertyStore *props = aiCreatePropertyStore();
    if (!props)
        return vv_error_set(VV_ERR_NOMEM, "mesh: %s: out of memory", name);
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_RVC_FLAGS,
                               aiComponent_NORMALS | aiComponent_TANGENTS_AND_BITANGENTS |
                                   aiComponent_COLORS | aiComponent_TEXCOORDS |
                                   aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS |
                                   aiComponent_TEXTURES | aiComponent_LIGHTS | aiComponent_CAMERAS |
                                   aiComponent_MATERIALS);
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_SBP_REMOVE,
                               aiPrimitiveType_POINT | aiPrimitiveType_LINE);
    unsigned flags = aiProcess_RemoveComponent | aiProcess_Triangulate |
                     aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices |
                     aiProcess_SortByPType | aiProcess_FindDegenerates;
    const struct aiScene *sc = aiImportFileExWithProperties(path, flags, NULL, props);
    aiReleasePropertyStore(props);
    if (!sc) {
        const char *why = aiGetErrorString();
        return vv_error_set(VV_ERR_FORMAT, "mesh: %s: %s", name, why && *why ? why : "unreadable");
    }
    size_t nv = 0, nt = 0;
    for (unsigned i = 0; i < sc->mNumMeshes; i++) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
            continue;
        nv += am->mNumVertices;
        nt += am->mNumFaces;
    }
    if (nt == 0) {
        aiReleaseImport(sc);
        return vv_error_set(VV_ERR_FORMAT, "mesh: %s: no triangles", name);
    }
    vv_mesh *m = NULL;
    if ((s = vv_mesh_new(&m)) != VV_OK || (s = vv_mesh_reserve(m, nv, nt)) != VV_OK) {
        aiReleaseImport(sc);
        vv_mesh_free(m);
        return vv_error_prefix(s, "mesh: %s", name);
    }
    for (unsigned i = 0; i < sc->mNumMeshes && s == VV_OK; i++) {
        const struct aiMesh *am = sc->mMeshes[i];
        if (!(am->mPrimitiveTypes & aiPrimitiveType_TRIANGLE))
            continue;
        uint32_t base = (uint32_t)m->n_vertices;
        for (unsigned v = 0; v < am->mNumVertices; v++) {
            const struct aiVector3D *p = &am->mVertices[v];
            m->positions[3 * m->n_vertices] = p->x;
            m->positions[3 * m->n_vertices + 1] = p->y;
            m->positions[3 * m->n_vertices + 2] = p->z;
            m->n_vertices++;
        }
        for (unsigned f = 0; f < am->mNumFaces && s == VV_OK; f++) {
            const struct aiFace *face = &am->mFaces[f];
            if (face->mNumIndices != 3)
                continue;
            s = vv_mesh_add_triangle(m, base + face->mIndices[0], base + face->mIndices[1],
                                     base + face->mIndices[2]);
        }
    }
    aiReleaseImport(sc);
    if (s == VV_OK && m->n_triangles == 0)
        s = vv_error_set(VV_ERR_FORMAT, "mesh: %s: no triangles", name);
    if (s == VV_OK)
        s = vv_mesh_compute_normals(m);
    if (s != VV_OK) {
        vv_mesh_free(m);
        return vv_error_prefix(s, "mesh: %s", name);
    }
    *out = m;
    return VV_OK;
}

/* The Assimp exporter id for a file name's extension, or NULL. */
static const char *
export_format(const char *path) {
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/'))
        return NULL;
    if (strcasecmp(dot, ".ply") == 0)
        return "plyb";
    if (strcasecmp(dot, ".obj") == 0)
        return "objnomtl";
    if (strcasecmp(dot, ".stl") == 0)
        return "stlb";
    return NULL;
}

vv_status
vv_mesh_save(const vv_mesh *m, const char *path) {
    if (!m || !path)
        return vv_error_set(VV_ERR_INVALID, "mesh: NULL argument");
    const char *name = vv_path_basename(path);
    const char *fmt = export_format(path);
    if (!fmt)
        return vv_error_set(VV_ERR_INVALID, "mesh: %s: unknown extension (use .ply, .obj or .stl)",
                            name);
    if (m->n_triangles == 0)
        return vv_error_set(VV_ERR_INVALID, "mesh: %s: the mesh has no triangles", name);
    if (m->n_vertices > UINT32_MAX || m->n_triangles > UINT32_MAX)
        return vv_error_set(VV_ERR_LIMIT, "mesh: %s: too large for the exporter", name);

    /* A one-mesh scene in Assimp's structures, owned here (not by Assimp). */
    struct aiScene sc;
    struct aiNode root;
    struct aiMesh am;
    struct aiMaterial mat;
    memset(&sc, 0, sizeof sc);
    memset(&root, 0, sizeof root);
    memset(&am, 0, sizeof am);
    memset(&mat, 0, sizeof mat);
    struct aiMesh *meshes[1] = {&am};
    struct aiMaterial *mats[1] = {&mat};
    unsigned mesh_index = 0;
    struct aiMaterialProperty *no_props[1] = {NULL};
    mat.mProperties = no_props;
    mat.mNumAllocated = 1;
    root.mName.length = 4;
    memcpy(root.mName.data, "root", 5);
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++)
            (&root.mTransformation.a1)[4 * r + c] = r == c ? 1.0f : 0.0f;
    root.mNumMeshes = 1;
    root.mMeshes = &mesh_index;
    sc.mRootNode = &root;
    sc.mNumMeshes = 1;
    sc.mMeshes = meshes;
    sc.mNumMaterials = 1;
    sc.mMaterials = mats;

    am.mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
    am.mNumVertices = (unsigned)m->n_vertices;
    am.mNumFaces = (unsigned)m->n_triangles;
    am.mVertices = malloc(m->n_vertices * sizeof *am.mVertices);
    am.mNormals = m->normals ? malloc(m->n_vertices * sizeof *am.mNormals) : NULL;
    am.mFaces = malloc(m->n_triangles * sizeof *am.mFaces);
    int ok = am.mVertices && am.mFaces && (!m->normals || am.mNormals);
    if (ok) {
        for (size_t i = 0; i < m->n_vertices; i++) {
            am.mVertices[i].x = m->positions[3 * i];
            am.mVertices[i].y = m->positions[3 * i + 1];
            am.mVertices[i].z = m->positions[3 * i + 2];
            if (m->normals) {
                am.mNormals[i].x = m->normals[3 * i];
                am.mNormals[i].y = m->normals[3 * i + 1];
                am.mNormals[i].z = m->normals[3 * i + 2];
            }
        }
        for (size_t t = 0; t < m->n_triangles; t++) {
            am.mFaces[t].mNumIndices = 3;
            am.mFaces[t].mIndices = m->triangles + 3 * t;
        }
    }
    vv_status s = VV_OK;
    if (!ok) {
        s = vv_error_set(VV_ERR_NOMEM, "mesh: %s: out of memory", name);
    } else {
        /* exported to memory and written through an atomic file, so a full
         * disk or a killed process never leaves a partial mesh (Assimp's own
         * file writer does not check its writes) */
        const struct aiExportDataBlob *blob = aiExportSceneToBlob(&sc, fmt, 0);
        if (!blob) {
            const char *why = aiGetErrorString();
            s = vv_error_set(VV_ERR_IO, "mesh: %s: %s", name,
                             why && *why ? why : "the exporter failed");
        } else {
            vv_atomic_file af;
            s = vv_atomic_file_open(&af, path);
            if (s != VV_OK) {
                s = vv_error_prefix(s, "mesh");
            } else if (fwrite(blob->data, 1, blob->size, af.fp) != blob->size) {
                s = vv_error_set(VV_ERR_IO, "mesh: %s: write failed: %s", name, strerror(errno));
                vv_atomic_file_abort(&af);
            } else if ((s = vv_atomic_file_commit(&af)) != VV_OK) {
                s = vv_error_prefix(s, "mesh");
            }
            aiReleaseExportBlob(blob);
        }
    }
    free(am.mVertices);
    free(am.mNormals);
    free(am.mFaces);
    return s;
}
