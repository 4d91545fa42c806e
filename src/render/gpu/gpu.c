/*
 * The GPU ray caster (renderer "gpu"): direct volume ray casting in a
 * Vulkan 1.2 compute shader (raycast.comp, compiled to SPIR-V by glslc at
 * build time and embedded), on any Vulkan device: a GPU, or Mesa's lavapipe
 * on the CPU. The method is the CPU ray caster's (src/render/raycast;
 * Levoy, IEEE CG&A 1988; the VolVis paper, section 5), and everything that
 * decides the image is prepared by the same code on the host: the voxel
 * cache (values in stored units, the octahedral gradient codes, the
 * subvolumes' min/max: sample.h), the transfer-function tables with the
 * opacity corrected for the step and the subvolume distances (classify.h),
 * the lights and shading constants (shade.h) and the camera rays
 * (vv_camera_rays). The shader repeats the per-sample arithmetic, so the
 * images agree with raycast's to rounding (tests/render/test_gpu.c).
 *
 * Per renderer: one Vulkan context on the device of option `device` (auto:
 * the first real GPU, else the first device); the volume (each channel's)
 * as 3-D images (values as R16 unorm or R32 float, gradient codes as RG8
 * int, gradient magnitudes as R32 float for a 2-D transfer function)
 * uploaded when it changes, and the subvolumes' min/max and distances when
 * they change; per frame the tables, the uniform block, one dispatch of 8 x
 * 8 pixels a workgroup and the copy back of the RGBA float image and depth
 * (and keys, in a region render). vv_render_stats.device_ms gets the
 * device's time for the frame's commands, upload_bytes the volume data
 * sent.
 *
 * The brick cache: a region whose voxels the driver names by their source
 * (vv_render_region.from: bricks and pyramid nodes out of core, the bricks
 * of a volume over the device's memory) keeps its images on the device,
 * keyed by (source volume and its change count, level, box), within the
 * device budget (option device_memory_mb), least recently used out; a
 * region found there is drawn without uploading its voxels
 * (vv_render_stats.cache_hits, else cache_misses). Each region is still
 * one dispatch of its own, and the driver still reads its voxels on the
 * host (their subvolume min/max and transfer-function tables come from
 * them); what the cache saves is the upload and the gradient codes.
 *
 * Draws one volume object (up to GPU_MAX_CH channels under the blend
 * rules) in composite, MIP, MinIP, X-ray, iso and attenuated-MIP mode
 * (napari's: the ray caster's parameters, vv_vatten_prepare, and
 * definition, project.c; regions give VV_REGION_ATTENUATED_MAX's maxima
 * and exponent sums) with a 1-D or 2-D transfer function or a threshold,
 * shading, lights and cut planes; regions (the out-of-core drivers; a
 * region of several channels under the composite rule, the drivers giving
 * the additive and maximum rules a pass a channel); a volume over option
 * device_memory_mb or the device's 3-D image side brick by brick. Refused
 * in one line: several volume objects, more channels, channels by bricks,
 * solid and image textures and label colours (raycast draws them).
 * Thread-safety: a renderer serves one render at a time (render.h).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "render/classify.h"
#include "render/drivers.h"
#include "render/frame.h"
#include "render/gpu/vk.h"
#include "render/project.h"
#include "render/ray.h"
#include "render/registry.h"
#include "render/sample.h"
#include "render/shade.h"
#include "volvis/render.h"
#include "volvis/source.h"
#include "volvis/sys/renderer.h"

#if VV_HAVE_VULKAN
static const uint32_t raycast_spv[] =
#include "gpu_raycast.spv.h"
    ;
#endif

/* The channels of a multi-channel object the shader draws at most. */
#define GPU_MAX_CH 4

/* The shader's uniform block (std140: every member 16 bytes). */
typedef struct gpu_ubo {
    float o00[4], ox[4], oy[4], d00[4], dx[4], dy[4];
    float w2i[3][4];
    float nrm[3][4];
    float amb[4], bg[4], base[4];
    float ldir[VV_MAX_LIGHTS][4], lpos[VV_MAX_LIGHTS][4], kd[VV_MAX_LIGHTS][4],
        ks[VV_MAX_LIGHTS][4];
    float planes[2 * VV_MAX_CUT_PLANES][4];
    int32_t dims[4], bdims[4], misc[4], clipd[4];
    float p0[4];                /* dt, early termination, iso (stored units), 0 */
    float rlo[4], rhi[4];       /* a region's owned samples (open sides: -+1e30) */
    int32_t roff[4];            /* its voxels' offset; [3]: 1 in a region render */
    int32_t rect[4];            /* its pixel rectangle x0, y0, x1, y1 (x1 <= x0: all) */
    float p2[4];                /* 2-D TF: table index -> value bin, |gradient| -> bin */
    float chp[GPU_MAX_CH][4];   /* per channel: table lo, table scale, value scale, MIP floor */
    float chq[GPU_MAX_CH][4];   /* per channel: MIP stop */
    int32_t chf[GPU_MAX_CH][4]; /* per channel: F_INTEGER | F_NORMALS */
    int32_t chn[4];             /* channels (0: one-channel object), blend rule */
    float att[4];               /* attenuated MIP (vv_vatten): lo, inv_range, qoff, vmax */
    float attk[4]; /* its k, a region's exponent per sample (k step_scale), 1: early stop */
} gpu_ubo;

/* the frame's flags (misc[3]) and a channel's (chf[k][0]) */
enum { F_SHADING = 1, F_SKIPPING = 4, F_LUT2D = 32 };
/* a region render: the opacity in front of it in B_FRONT
 * (vv_render_region.front); its rectangle (rect) alone dispatched */
enum { F_FRONT = 64, F_RECT = 128 };
enum { F_NORMALS = 2, F_INTEGER = 16 };

/* The buffers the shader reads and writes (bindings 0, 3 .. 9, 11 and 18);
 * the uploads (B_UBO .. B_FRONT) come first, then the outputs. */
enum { B_UBO, B_LUT, B_SPEC, B_DIST, B_MM, B_LUT2, B_FRONT, B_RGBA, B_DEPTH, B_KEY, N_BUF };
static const int binding_of[N_BUF] = {0, 3, 4, 5, 6, 11, 18, 7, 8, 9};
/* the 3-D images: channel k's values at I_VALUES + 2 k, its gradient codes
 * at I_NORMALS + 2 k (k = 0: a one-channel object's), the gradient
 * magnitudes of a 2-D transfer function at I_GMAG */
enum { I_VALUES, I_NORMALS, I_GMAG = 2 * GPU_MAX_CH, N_IMG };
static const int image_binding[N_IMG] = {1, 2, 12, 15, 13, 16, 14, 17, 10};
#define N_BINDINGS 19

#if VV_HAVE_VULKAN
/* A brick on the device (the brick cache): the voxels of one region known
 * by its source's volume, that volume's change count, the level and the
 * box (vv_render_region.from), as the images the shader samples. */
typedef struct gpu_brick {
    vv_volume *from; /* reference held, so that the address stays unique */
    uint64_t modified;
    int level, offset[3], dims[3];
    vv_vk_image img[3]; /* values, gradient codes, gradient magnitudes */
    int part[3];        /* each image: 0 none, 1 a 1 x 1 x 1 stand-in, 2 the brick's array */
    VkDeviceSize bytes; /* of the arrays (part 2) */
    uint64_t used;      /* the cache's clock when last drawn */
} gpu_brick;
#endif

typedef struct gpu_state {
    vv_vcache_set vc;         /* the host's voxel caches (sample.h) */
    double early_termination; /* option */
    int skipping;             /* option empty_space_skipping */
    int device;               /* option device: -1 auto */
    double budget_mb;         /* option device_memory_mb: -1 auto */
    int brick_cache;          /* option brick_cache */
    /* a volume over the device budget is drawn brick by brick by the
     * brick driver (drv_render_bricks) with this state's region renders,
     * its bricks' min/max computed once a volume */
    const vv_volume *bricks_vol;
    uint64_t bricks_modified;
    int bricks_side, bricks_nb[3];
    float *bricks_mm; /* per brick: min, max (data units) */
    vv_source *bricks_src;
    /* the X-ray table of the last region render in xray mode, which
     * classifies the summed regions' means (vv_region_image.classify) */
    vv_xray_table xray;
#if VV_HAVE_VULKAN
    vv_vk vk;
    int ready; /* vk, pipeline and descriptors made */
    VkDescriptorSetLayout dsl;
    VkPipelineLayout layout;
    VkPipeline pipe;
    VkDescriptorPool pool;
    VkDescriptorSet set;
    VkSampler sampler;
    vv_vk_image img[N_IMG]; /* values, gradient codes, gradient magnitudes */
    /* what each image was made from: the cache's volume, its change count
     * and the array (NULL: a 1 x 1 x 1 stand-in) */
    struct {
        const vv_volume *vol;
        uint64_t modified;
        const void *data;
        int made;
    } from[N_IMG];
    vv_vk_buffer buf[N_BUF]; /* device-local */
    vv_vk_buffer staging;    /* host: the frame's uploads */
    /* what the subvolume buffers on the device hold, so that they go up only
     * when it changes (a 2048^3 volume has 134 M subvolumes: 1 GiB of
     * min/max): the min/max of cache mm_vol at mm_modified, and each
     * channel's distances from the tables of dist_key[k] over dist_vol[k] */
    const vv_volume *mm_vol;
    uint64_t mm_modified;
    size_t mm_blocks;
    int dist_n;
    const vv_volume *dist_vol[GPU_MAX_CH];
    uint64_t dist_modified[GPU_MAX_CH];
    vv_vtables_key dist_key[GPU_MAX_CH];
    vv_vk_buffer readback; /* host: the image back */
    /* the brick cache: the regions' voxels kept on the device between
     * frames within the device budget, least recently used out */
    gpu_brick **bricks;
    int n_bricks, cap_bricks;
    VkDeviceSize brick_bytes;
    uint64_t brick_clock;
#endif
} gpu_state;

#if VV_HAVE_VULKAN

/* Brick @p i of the cache out of it (its images, its reference). */
static void
brick_evict(gpu_state *st, int i) {
    gpu_brick *b = st->bricks[i];
    for (int p = 0; p < 3; p++)
        vv_vk_image_free(&st->vk, &b->img[p]);
    st->brick_bytes -= b->bytes;
    vv_volume_free(b->from);
    free(b);
    st->bricks[i] = st->bricks[--st->n_bricks];
}

static void
brick_cache_clear(gpu_state *st) {
    while (st->n_bricks > 0)
        brick_evict(st, st->n_bricks - 1);
    free(st->bricks);
    st->bricks = NULL;
    st->cap_bricks = 0;
    st->brick_bytes = 0;
}

static void
release_device(gpu_state *st) {
    vv_vk *vk = &st->vk;
    brick_cache_clear(st);
    if (!vk->dev)
        return;
    vk->f.vkDestroyPipeline(vk->dev, st->pipe, NULL);
    vk->f.vkDestroyPipelineLayout(vk->dev, st->layout, NULL);
    vk->f.vkDestroyDescriptorPool(vk->dev, st->pool, NULL);
    vk->f.vkDestroyDescriptorSetLayout(vk->dev, st->dsl, NULL);
    vk->f.vkDestroySampler(vk->dev, st->sampler, NULL);
    for (int i = 0; i < N_IMG; i++)
        vv_vk_image_free(vk, &st->img[i]);
    for (int i = 0; i < N_BUF; i++)
        vv_vk_buffer_free(vk, &st->buf[i]);
    vv_vk_buffer_free(vk, &st->staging);
    vv_vk_buffer_free(vk, &st->readback);
    vv_vk_close(vk);
    st->ready = 0;
    memset(st->from, 0, sizeof st->from);
    st->mm_vol = NULL;
    st->mm_blocks = 0;
    st->dist_n = -1;
    st->pipe = VK_NULL_HANDLE;
    st->layout = VK_NULL_HANDLE;
    st->pool = VK_NULL_HANDLE;
    st->dsl = VK_NULL_HANDLE;
    st->sampler = VK_NULL_HANDLE;
}

/* The context, the pipeline of the embedded shader and its descriptor set. */
static vv_status
open_device(gpu_state *st) {
    if (st->ready)
        return VV_OK;
    vv_status s = vv_vk_open(&st->vk, st->device);
    if (s != VV_OK) {
        vv_vk_close(&st->vk);
        return s;
    }
    vv_vk *vk = &st->vk;
    VkDescriptorSetLayoutBinding b[N_BINDINGS];
    for (int i = 0; i < N_BINDINGS; i++) {
        b[i] = (VkDescriptorSetLayoutBinding){
            .binding = (uint32_t)i,
            .descriptorType = i == 0 ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER
                              : i == 1 || i == 2 || i == 10 || (i >= 12 && i <= 17)
                                  ? VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER
                                  : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
            .descriptorCount = 1,
            .stageFlags = VK_SHADER_STAGE_COMPUTE_BIT};
    }
    const VkDescriptorSetLayoutCreateInfo li = {
        .sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO,
        .bindingCount = N_BINDINGS,
        .pBindings = b};
    s = vv_vk_check(vk, vk->f.vkCreateDescriptorSetLayout(vk->dev, &li, NULL, &st->dsl),
                    "vkCreateDescriptorSetLayout");
    const VkPipelineLayoutCreateInfo pli = {.sType = VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO,
                                            .setLayoutCount = 1,
                                            .pSetLayouts = &st->dsl};
    if (s == VV_OK)
        s = vv_vk_check(vk, vk->f.vkCreatePipelineLayout(vk->dev, &pli, NULL, &st->layout),
                        "vkCreatePipelineLayout");
    VkShaderModule mod = VK_NULL_HANDLE;
    const VkShaderModuleCreateInfo mi = {.sType = VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO,
                                         .codeSize = sizeof raycast_spv,
                                         .pCode = raycast_spv};
    if (s == VV_OK)
        s = vv_vk_check(vk, vk->f.vkCreateShaderModule(vk->dev, &mi, NULL, &mod),
                        "vkCreateShaderModule");
    const VkComputePipelineCreateInfo ci = {
        .sType = VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO,
        .stage = {.sType = VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                  .stage = VK_SHADER_STAGE_COMPUTE_BIT,
                  .module = mod,
                  .pName = "main"},
        .layout = st->layout};
    if (s == VV_OK)
        s = vv_vk_check(
            vk, vk->f.vkCreateComputePipelines(vk->dev, VK_NULL_HANDLE, 1, &ci, NULL, &st->pipe),
            "vkCreateComputePipelines");
    if (mod)
        vk->f.vkDestroyShaderModule(vk->dev, mod, NULL);
    const VkDescriptorPoolSize ps[3] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1},
                                        {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, N_IMG},
                                        {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 9}};
    const VkDescriptorPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO,
                                           .maxSets = 1,
                                           .poolSizeCount = 3,
                                           .pPoolSizes = ps};
    if (s == VV_OK)
        s = vv_vk_check(vk, vk->f.vkCreateDescriptorPool(vk->dev, &pi, NULL, &st->pool),
                        "vkCreateDescriptorPool");
    const VkDescriptorSetAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO,
                                            .descriptorPool = st->pool,
                                            .descriptorSetCount = 1,
                                            .pSetLayouts = &st->dsl};
    if (s == VV_OK)
        s = vv_vk_check(vk, vk->f.vkAllocateDescriptorSets(vk->dev, &ai, &st->set),
                        "vkAllocateDescriptorSets");
    const VkSamplerCreateInfo si = {.sType = VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO,
                                    .magFilter = VK_FILTER_NEAREST,
                                    .minFilter = VK_FILTER_NEAREST,
                                    .addressModeU = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                                    .addressModeV = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                                    .addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE,
                                    .unnormalizedCoordinates = VK_FALSE};
    if (s == VV_OK)
        s = vv_vk_check(vk, vk->f.vkCreateSampler(vk->dev, &si, NULL, &st->sampler),
                        "vkCreateSampler");
    if (s != VV_OK) {
        st->ready = 1; /* so that release_device frees what was made */
        release_device(st);
        return s;
    }
    st->ready = 1;
    return VV_OK;
}

/* Makes @p b at least @p size bytes (device-local or host). */
static vv_status
ensure_buffer(gpu_state *st, vv_vk_buffer *b, VkDeviceSize size, VkBufferUsageFlags usage,
              int host) {
    if (b->buf && b->size >= size)
        return VV_OK;
    vv_vk_buffer_free(&st->vk, b);
    /* room to grow a little, so a resized view does not reallocate each frame */
    return vv_vk_buffer_new(&st->vk, size + size / 4, usage, host, b);
}

/* The array @p what (0 values, 1 gradient codes, 2 gradient magnitudes) of
 * cache @p c, or NULL where it has none (c NULL: none). */
static const void *
cache_array(const vv_vcache *c, int what) {
    return !c          ? NULL
           : what == 0 ? (c->q16 ? (const void *)c->q16 : (const void *)c->f32)
           : what == 1 ? (const void *)c->nrm
                       : (const void *)c->gmag;
}

/* Bytes of array @p what of cache @p c on the device. */
static VkDeviceSize
array_bytes(const vv_vcache *c, int what) {
    const VkDeviceSize n = (VkDeviceSize)c->nx * (VkDeviceSize)c->ny * (VkDeviceSize)c->nz;
    return what == 0 ? n * (c->q16 ? 2 : 4) : what == 1 ? 2 * n : 4 * n;
}

/* Image *@p im made anew from @p data, array @p what of cache @p c (NULL
 * data: a 1 x 1 x 1 image standing for an array there is not); records the
 * copy into the command buffer being recorded, through the staging buffer
 * from *used on (*used: bytes of staging used), and adds the array's bytes
 * to *sent. With @p dry, only adds to *used the bytes it would take: the
 * caller makes the staging buffer large enough first, since a copy
 * recorded from it must not see it replaced. */
static vv_status
image_put(gpu_state *st, vv_vk_image *im, const vv_vcache *c, int what, const void *data,
          VkDeviceSize *used, int dry, VkDeviceSize *sent) {
    vv_vk *vk = &st->vk;
    static const uint8_t no_gradient[2] = {0x80, 0x80}; /* VV_OCT_ZERO */
    static const float zero = 0;
    const int one[3] = {1, 1, 1};
    const int dims[3] = {data ? c->nx : 1, data ? c->ny : 1, data ? c->nz : 1};
    const size_t bytes = data ? (size_t)array_bytes(c, what) : what == 1 ? 2 : 4;
    const VkFormat fmt = what == 1                     ? VK_FORMAT_R8G8_SINT
                         : what == 0 && data && c->q16 ? VK_FORMAT_R16_UNORM
                                                       : VK_FORMAT_R32_SFLOAT;
    const void *src = data ? data : what == 1 ? (const void *)no_gradient : (const void *)&zero;
    if (dry) {
        *used += (bytes + 15) & ~(size_t)15;
        return VV_OK;
    }
    vv_vk_image_free(vk, im);
    vv_status s = vv_vk_image_new(vk, data ? dims : one, fmt, im);
    if (s != VV_OK)
        return vv_error_prefix(s, "the volume (%d x %d x %d)", dims[0], dims[1], dims[2]);
    memcpy((unsigned char *)st->staging.map + *used, src, bytes);
    vv_vk_copy_to_image(vk, &st->staging, *used, im);
    *used += (bytes + 15) & ~(size_t)15;
    if (data)
        *sent += bytes;
    return VV_OK;
}

/* Image @p slot on the device from cache @p c (NULL: none) when it changed:
 * @p what 0 its values, 1 its gradient codes, 2 its gradient magnitudes, a
 * 1 x 1 x 1 image standing for an array it does not have (image_put). */
static vv_status
upload_image(gpu_state *st, int slot, const vv_vcache *c, int what, VkDeviceSize *used, int dry,
             VkDeviceSize *sent) {
    const void *data = cache_array(c, what);
    if (st->from[slot].made && st->from[slot].data == data &&
        (!data || (st->from[slot].vol == c->vol && st->from[slot].modified == c->modified)))
        return VV_OK;
    if (!dry)
        st->from[slot].made = 0;
    vv_status s = image_put(st, &st->img[slot], c, what, data, used, dry, sent);
    if (s != VV_OK || dry)
        return s;
    st->from[slot].vol = c ? c->vol : NULL;
    st->from[slot].modified = c ? c->modified : 0;
    st->from[slot].data = data;
    st->from[slot].made = 1;
    return VV_OK;
}

/* ---- the brick cache ---------------------------------------------------------- */

/* The device budget in bytes (option device_memory_mb; auto: three
 * quarters of the device's largest local heap), 0: no limit. */
static double
device_budget(const gpu_state *st) {
    if (st->budget_mb >= 0)
        return st->budget_mb * 1048576.0;
    double budget = 0;
    for (uint32_t h = 0; h < st->vk.mem.memoryHeapCount; h++)
        if (st->vk.mem.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT)
            budget = fmax(budget, 0.75 * (double)st->vk.mem.memoryHeaps[h].size);
    return budget;
}

/* The cached brick of region @p rg's voxels (its key: vv_render_region.from),
 * found or added empty, marked used. Errors: VV_ERR_NOMEM. */
static vv_status
brick_lookup(gpu_state *st, const vv_render_region *rg, gpu_brick **out) {
    const vv_volume *v = rg->voxels;
    st->brick_clock++;
    for (int i = 0; i < st->n_bricks; i++) {
        gpu_brick *b = st->bricks[i];
        if (b->from == rg->from && b->modified == rg->from->modified && b->level == rg->level &&
            !memcmp(b->offset, rg->offset, sizeof b->offset) &&
            !memcmp(b->dims, v->dims, sizeof b->dims)) {
            b->used = st->brick_clock;
            *out = b;
            return VV_OK;
        }
    }
    if (st->n_bricks == st->cap_bricks) {
        const int cap = st->cap_bricks ? 2 * st->cap_bricks : 64;
        gpu_brick **nb = realloc(st->bricks, sizeof *nb * (size_t)cap);
        if (!nb)
            return vv_error_set(VV_ERR_NOMEM, "gpu: out of memory (brick cache of %d)", cap);
        st->bricks = nb;
        st->cap_bricks = cap;
    }
    gpu_brick *b = calloc(1, sizeof *b);
    if (!b)
        return vv_error_set(VV_ERR_NOMEM, "gpu: out of memory (brick cache)");
    b->from = vv_volume_ref((vv_volume *)rg->from);
    b->modified = rg->from->modified;
    b->level = rg->level;
    memcpy(b->offset, rg->offset, sizeof b->offset);
    memcpy(b->dims, v->dims, sizeof b->dims);
    b->used = st->brick_clock;
    st->bricks[st->n_bricks++] = b;
    *out = b;
    return VV_OK;
}

/* The least recently used bricks other than @p keep out until the cache
 * and @p grow bytes more fit the device budget (or @p keep alone is left). */
static void
brick_trim(gpu_state *st, const gpu_brick *keep, VkDeviceSize grow) {
    const double budget = device_budget(st);
    while (budget > 0 && (double)(st->brick_bytes + grow) > budget) {
        int lru = -1;
        for (int i = 0; i < st->n_bricks; i++)
            if (st->bricks[i] != keep && (lru < 0 || st->bricks[i]->used < st->bricks[lru]->used))
                lru = i;
        if (lru < 0)
            return;
        brick_evict(st, lru);
    }
}

/* Image @p what of cached brick @p b from cache @p c: the array when
 * @p real (and the brick has not got it yet), else a stand-in where it has
 * no image; as upload_image. *grow gets the bytes of arrays it adds. */
static vv_status
upload_brick(gpu_state *st, gpu_brick *b, const vv_vcache *c, int what, int real,
             VkDeviceSize *used, int dry, VkDeviceSize *sent, VkDeviceSize *grow) {
    const void *data = real ? cache_array(c, what) : NULL;
    if (b->part[what] == 2 || (!data && b->part[what] == 1))
        return VV_OK;
    if (dry) {
        if (data)
            *grow += array_bytes(c, what);
        return image_put(st, &b->img[what], c, what, data, used, 1, sent);
    }
    b->part[what] = 0;
    const VkDeviceSize at = *used;
    vv_status s = image_put(st, &b->img[what], c, what, data, used, 0, sent);
    if (s == VV_ERR_NOMEM && st->n_bricks > 1) {
        /* the device is fuller than the budget thought (other programs,
         * a budget over its memory): every other brick out, once more */
        vv_error_clear();
        for (int i = st->n_bricks - 1; i >= 0; i--)
            if (st->bricks[i] != b)
                brick_evict(st, i);
        *used = at;
        s = image_put(st, &b->img[what], c, what, data, used, 0, sent);
    }
    if (s != VV_OK)
        return s;
    b->part[what] = data ? 2 : 1;
    if (data) {
        b->bytes += array_bytes(c, what);
        st->brick_bytes += array_bytes(c, what);
    }
    return VV_OK;
}

/* Pixels px0 .. px1 - 1 of the image from the readback buffer (RGBA, then
 * depth, of npx pixels each), columns x0 .. x1 - 1 of each of their rows
 * alone when that is not the whole row (a region's rectangle), in slices
 * on the frame's threads: one thread copies a 3840 x 2160 float image
 * (166 MB) at a few GB/s, several times the device's time for the frame. */
static void
copy_back(vv_image *out, float *key, const unsigned char *r, size_t npx, size_t px0, size_t px1,
          int x0, int x1, int threads) {
    const size_t W = (size_t)out->width;
    if (x0 > 0 || (size_t)x1 < W) {
        for (size_t row = px0; row < px1; row += W) {
            const size_t a = row + (size_t)x0, m = (size_t)(x1 - x0);
            memcpy(out->rgba + 4 * a, r + 16 * a, 16 * m);
            memcpy(out->depth + a, r + 16 * npx + 4 * a, 4 * m);
            if (key)
                memcpy(key + a, r + 20 * npx + 4 * a, 4 * m);
        }
        return;
    }
    const size_t slice = (size_t)1 << 16; /* pixels a piece */
    const long n = (long)((px1 - px0 + slice - 1) / slice);
    const int nt = threads > 0 ? threads : vv_threads_get();
#pragma omp parallel for schedule(static) num_threads(nt) if (n > 1)
    for (long i = 0; i < n; i++) {
        const size_t a = px0 + (size_t)i * slice, m = px1 - a < slice ? px1 - a : slice;
        memcpy(out->rgba + 4 * a, r + 16 * a, 16 * m);
        memcpy(out->depth + a, r + 16 * npx + 4 * a, 4 * m);
        if (key)
            memcpy(key + a, r + 20 * npx + 4 * a, 4 * m);
    }
}

static void
vec4_of(float out[4], vv_vec3 v) {
    out[0] = (float)v.x;
    out[1] = (float)v.y;
    out[2] = (float)v.z;
    out[3] = 0;
}

/* The one volume object the World shows (NULL: none), or an error. */
static vv_status
find_object(const vv_world *w, const vv_object **out) {
    *out = NULL;
    int n = 0;
    for (int i = 0; i < w->n_objects; i++) {
        const vv_object *ob = w->objects[i];
        if (!ob->visible || ob->type != VV_OBJECT_VOLUME || !ob->volume)
            continue;
        if (n++ == 0)
            *out = ob;
    }
    if (n > 1)
        return vv_error_set(VV_ERR_UNSUPPORTED,
                            "the gpu renderer draws one volume object, the World shows %d "
                            "(raycast draws several)",
                            n);
    return VV_OK;
}

/* A whole frame (@p rg NULL) or region @p rg of its one object (the
 * region contract of include/volvis/sys/renderer.h: the samples it owns,
 * from its voxels; no background; *key per pixel for projections). */
static vv_status
render_frame(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
             const vv_render_region *rg, vv_image *out, float *key) {
    gpu_state *st = state;
    const vv_object *obj;
    vv_status s = find_object(w, &obj);
    if (s != VV_OK)
        return s;
    s = open_device(st);
    if (s != VV_OK)
        return s;
    vv_vk *vk = &st->vk;
    st->vc.frame++;

    gpu_ubo u;
    memset(&u, 0, sizeof u);
    float ambient[3], bg[3];
    vv_frame_colours(w, rg != NULL, ambient, bg);
    for (int a = 0; a < 3; a++)
        u.bg[a] = bg[a];
    vv_vlight lights[VV_MAX_LIGHTS];
    const int n_lights = vv_vlights_prepare(lights, w, view);
    vv_camera_rays cam;
    vv_camera_rays_init(&cam, view);
    vec4_of(u.o00, cam.o00);
    vec4_of(u.ox, cam.ox);
    vec4_of(u.oy, cam.oy);
    vec4_of(u.d00, cam.d00);
    vec4_of(u.dx, cam.dx);
    vec4_of(u.dy, cam.dy);
    u.misc[0] = view->width;
    u.misc[1] = view->height;

    /* the object's channels: one (the object itself), or the visible
     * channels of a multi-channel object, each as an object of its own
     * (vv_vchannel_object: its volume and transfer function) */
    int nch = 0; /* caches: 1 a one-channel object, 2 .. GPU_MAX_CH channels */
    vv_object chobj[GPU_MAX_CH];
    vv_vcache *cc[GPU_MAX_CH] = {NULL};
    /* a region's voxels known by their source (vv_render_region.from): kept
     * on the device in the brick cache, uploaded only when it lacks them */
    gpu_brick *brick = NULL;
    vv_vtables tabs[GPU_MAX_CH];
    int owns[GPU_MAX_CH] = {0};
    memset(tabs, 0, sizeof tabs);
    vv_vcache *c = NULL;              /* channel 0's cache: the grid and its subvolumes */
    const vv_vtables *tab = &tabs[0]; /* channel 0's tables */
    size_t nblocks = 1;
    /* the pixels dispatched and read back: the rows, the columns */
    int row0 = 0, row1 = view->height, col0 = 0, col1 = view->width;
    const vv_image *front = NULL; /* the opacity in front of a region (F_FRONT) */
    vv_vshading sh;               /* the object's shading constants (its specular table goes up) */
    const float *lut2d = NULL;    /* its 2-D transfer function's table, or NULL */
    if (obj) {
        if (!(obj->step > 0))
            return vv_error_set(VV_ERR_INVALID, "object '%s': step must be > 0", obj->name);
        const int multi = obj->n_channels > 1;
        if (multi) {
            const int shown = vv_vchannels_shown(obj);
            if (shown > GPU_MAX_CH)
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "object '%s' shows %d channels; the gpu renderer draws up to "
                                    "%d (raycast draws %d)",
                                    obj->name, shown, GPU_MAX_CH, VV_MAX_CHANNELS);
            if (rg && obj->blend != VV_BLEND_COMPOSITE)
                return vv_error_set(VV_ERR_UNSUPPORTED,
                                    "object '%s': by regions, the gpu renderer draws channels "
                                    "under the composite rule (the drivers draw the others a "
                                    "channel at a time)",
                                    obj->name);
            for (int k = 0; k < obj->n_channels; k++)
                if (obj->channels[k].visible && obj->channels[k].volume)
                    vv_vchannel_object(obj, &obj->channels[k], &chobj[nch++]);
        } else {
            chobj[nch++] = *obj;
            if (rg && rg->from && st->brick_cache && (s = brick_lookup(st, rg, &brick)) != VV_OK)
                return s;
        }
        const double dt = vv_vobject_step(obj);
        for (int k = 0; k < nch && s == VV_OK; k++) {
            const vv_object *ck = &chobj[k];
            s = vv_vcache_get(&st->vc, ck->volume, &cc[k]);
            if (s != VV_OK) {
                s = vv_error_prefix(s, "object '%s'", obj->name);
                break;
            }
            /* a cached brick's gradient codes are on the device already */
            if (ck->shading && (ck->mode == VV_MODE_COMPOSITE || ck->mode == VV_MODE_ISO) &&
                !(brick && brick->part[1] == 2)) {
                vv_vcache_need_normals(&st->vc, cc[k]);
                if (!cc[k]->nrm && opt && opt->stats)
                    opt->stats->gradients_at_samples++;
            }
            const float iso = (float)(ck->isovalue - cc[k]->qoff);
            s = vv_vtables_get(&st->vc, cc[k], ck, ck->mode, (float)dt, iso, st->skipping, 0,
                               &tabs[k], &owns[k]);
            if (s != VV_OK)
                break;
            vv_vextra x;
            vv_vextra_prepare(&x, ck, ck->mode, &tabs[k]);
            if (x.solid || x.labels || (ck->mode == VV_MODE_ISO && ck->texture.image)) {
                s = vv_error_set(VV_ERR_UNSUPPORTED,
                                 "object '%s' has a solid texture, an image texture or label "
                                 "colours; the gpu renderer draws 1-D and 2-D transfer "
                                 "functions and thresholds (raycast draws them)",
                                 obj->name);
                break;
            }
            if (x.lut2d && !cc[k]->gmag) {
                s = vv_error_set(VV_ERR_NOMEM,
                                 "object '%s': no gradient magnitudes for its 2-D transfer "
                                 "function",
                                 obj->name);
                break;
            }
            if (x.lut2d) {
                lut2d = x.lut2d;
                u.p2[0] = x.lut2_scale;
                u.p2[1] = x.g_scale;
            }
            if (k > 0 &&
                (cc[k]->nx != cc[0]->nx || cc[k]->ny != cc[0]->ny || cc[k]->nz != cc[0]->nz)) {
                s = vv_error_set(VV_ERR_INVALID, "object '%s': its channels differ in size",
                                 obj->name);
                break;
            }
            u.chp[k][0] = tabs[k].lut_lo;
            u.chp[k][1] = tabs[k].lut_scale;
            u.chp[k][2] = cc[k]->q16 ? 65535.0f : 1.0f;
            u.chp[k][3] = tabs[k].pdist ? tabs[k].plo : -INFINITY;
            u.chq[k][0] = tabs[k].pdist ? tabs[k].phi : INFINITY;
            const int normals = brick ? brick->part[1] == 2 || cc[k]->nrm : cc[k]->nrm != NULL;
            u.chf[k][0] = (cc[k]->q16 ? F_INTEGER : 0) | (normals ? F_NORMALS : 0);
        }
        c = cc[0];
        double w2i[3][4], i2w[3][4];
        int dims[3], n_planes = 0;
        vv_plane planes[2 * VV_MAX_CUT_PLANES];
        if (s == VV_OK)
            s = vv_vobject_prepare(&chobj[0], w, ambient, lights, n_lights, w2i, i2w, dims, planes,
                                   &n_planes, &sh);
        if (s != VV_OK) {
            for (int k = 0; k < nch; k++)
                if (owns[k])
                    vv_vtables_free(&tabs[k]);
            return s;
        }
        const vv_render_mode mode = obj->mode;
        const float iso = (float)(obj->isovalue - c->qoff);
        u.chn[0] = multi ? nch : 0;
        u.chn[1] = (int)obj->blend;
        for (int a = 0; a < 3; a++) {
            for (int b = 0; b < 4; b++)
                u.w2i[a][b] = (float)w2i[a][b];
            for (int b = 0; b < 3; b++)
                u.nrm[a][b] = sh.nrm[a][b];
            u.amb[a] = sh.amb[a];
            u.base[a] = sh.base[a];
        }
        for (int l = 0; l < n_lights; l++) {
            for (int a = 0; a < 3; a++) {
                u.ldir[l][a] = lights[l].dir[a];
                u.lpos[l][a] = lights[l].pos[a];
                u.kd[l][a] = sh.kd_col[l][a];
                u.ks[l][a] = sh.ks_col[l][a];
            }
            u.ldir[l][3] = lights[l].point ? 1.0f : 0.0f;
        }
        for (int p = 0; p < n_planes; p++) {
            vec4_of(u.planes[p], planes[p].n);
            u.planes[p][3] = (float)planes[p].d;
        }
        const int modes[] = {
            [VV_MODE_COMPOSITE] = 0, [VV_MODE_MIP] = 1, [VV_MODE_MINIP] = 2,
            [VV_MODE_XRAY] = 3,      [VV_MODE_ISO] = 4, [VV_MODE_ATTENUATED_MIP] = 5};
        u.dims[0] = c->nx;
        u.dims[1] = c->ny;
        u.dims[2] = c->nz;
        u.dims[3] = modes[mode];
        u.bdims[0] = c->bx;
        u.bdims[1] = c->by;
        u.bdims[2] = c->bz;
        u.bdims[3] = n_lights;
        u.misc[2] = n_planes;
        u.misc[3] = (obj->shading ? F_SHADING : 0) | (st->skipping && tab->bdist ? F_SKIPPING : 0) |
                    (lut2d ? F_LUT2D : 0);
        for (int a = 0; a < 3; a++)
            u.clipd[a] = rg ? (rg->dims[a] > 1 ? rg->dims[a] : 2) : dims[a];
        if (rg) {
            /* rays in the whole volume's index box, samples from the region's voxels */
            for (int a = 0; a < 3; a++) {
                u.rlo[a] = rg->lo[a] == -INFINITY ? -1e30f : (float)rg->lo[a];
                u.rhi[a] = rg->hi[a] == INFINITY ? 1e30f : (float)rg->hi[a];
                u.roff[a] = rg->offset[a];
            }
            u.roff[3] = 1;
            if (rg->x1 > rg->x0) { /* y1 <= y0 (off screen): every pixel outside */
                u.rect[0] = rg->x0;
                u.rect[1] = rg->y0;
                u.rect[2] = rg->x1;
                u.rect[3] = rg->y1;
                /* only the rectangle is dispatched and read back: the
                 * caller keeps the image clear outside it */
                row0 = rg->y0 > 0 ? rg->y0 : 0;
                row1 = rg->y1 < view->height ? rg->y1 : view->height;
                row1 = row1 > row0 ? row1 : row0;
                col0 = rg->x0 > 0 ? rg->x0 : 0;
                col1 = rg->x1 < view->width ? rg->x1 : view->width;
                col1 = col1 > col0 ? col1 : col0;
                if (col1 == col0)
                    row1 = row0; /* nothing to draw */
                u.misc[3] |= F_RECT;
            }
            /* early ray termination across the caller's regions (composite) */
            if (rg->front && mode == VV_MODE_COMPOSITE &&
                (!multi || obj->blend == VV_BLEND_COMPOSITE) && st->early_termination < 1) {
                front = rg->front;
                u.misc[3] |= F_FRONT;
            }
        }
        if (mode == VV_MODE_ATTENUATED_MIP && !multi) {
            /* napari's attenuated MIP, the ray caster's parameters (a
             * multi-channel object is drawn by its blend rule, as raycast
             * draws it) */
            vv_vatten att;
            if ((s = vv_vatten_prepare(&att, obj, c, (float)dt)) != VV_OK) {
                for (int k = 0; k < nch; k++)
                    if (owns[k])
                        vv_vtables_free(&tabs[k]);
                return s;
            }
            u.att[0] = att.lo;
            u.att[1] = att.inv_range;
            u.att[2] = att.qoff;
            u.att[3] = att.vmax;
            u.attk[0] = (float)att.k;
            /* a region's exponents weigh its step against the finest level's */
            u.attk[1] = (float)(att.k * (rg && rg->step_scale > 0 ? rg->step_scale : 1));
            /* (a real maximum below 0 grows as its scale shrinks: no early stop) */
            u.attk[2] = (double)att.vmax + (double)att.qoff >= 0 ? 1.0f : 0.0f;
        }
        if (rg && (mode == VV_MODE_XRAY || mode == VV_MODE_ATTENUATED_MIP)) {
            /* the table that classifies the summed means (vv_xray_table_classify),
             * or the attenuated maxima, whose keys are real values (value + qoff) */
            st->xray.lut_lo =
                tab->lut_lo + (mode == VV_MODE_ATTENUATED_MIP ? (float)c->qoff : 0.0f);
            st->xray.lut_scale = tab->lut_scale;
            memcpy(st->xray.lut, tab->lut, sizeof st->xray.lut);
        }
        u.p0[0] = (float)dt;
        u.p0[1] = (float)st->early_termination;
        u.p0[2] = iso;
        nblocks = (size_t)c->bx * (size_t)c->by * (size_t)c->bz;
    } else {
        u.misc[2] = 1; /* nothing to draw: one plane that cuts every ray */
        u.planes[0][3] = -1;
        u.dims[0] = u.dims[1] = u.dims[2] = 2;
        u.clipd[0] = u.clipd[1] = u.clipd[2] = 2;
        u.bdims[0] = u.bdims[1] = u.bdims[2] = 1;
        u.p0[0] = 1;
        u.chp[0][2] = 1;
    }

    /* the frame's uploads, in the staging buffer */
    const size_t npx = (size_t)view->width * (size_t)view->height;
    const VkDeviceSize sizes[N_BUF] = {sizeof u,
                                       (VkDeviceSize)VV_VC_LUT * 16 * GPU_MAX_CH,
                                       (VV_VC_SPEC + 1) * sizeof(float),
                                       (nblocks * (nch > 1 ? nch : 1) + 3) & ~(size_t)3,
                                       nblocks * 8,
                                       lut2d ? (VkDeviceSize)VV_VC_LUT2_G * VV_VC_LUT2_V * 16 : 16,
                                       front ? npx * 4 : 16,
                                       npx * 16,
                                       npx * 4,
                                       npx * 4};
    VkDeviceSize offs[N_BUF], total = 0;
    for (int i = 0; i < B_RGBA; i++) {
        offs[i] = total;
        total += (sizes[i] + 255) & ~(VkDeviceSize)255;
    }
    const VkBufferUsageFlags dst = VK_BUFFER_USAGE_TRANSFER_DST_BIT;
    /* the subvolumes' min/max and distances go up only when they changed */
    int mm_up =
        !c || st->mm_vol != c->vol || st->mm_modified != c->modified || st->mm_blocks != nblocks;
    int dist_up = st->dist_n != nch;
    for (int k = 0; k < nch; k++)
        dist_up |= owns[k] || st->dist_vol[k] != cc[k]->vol ||
                   st->dist_modified[k] != cc[k]->modified ||
                   memcmp(&st->dist_key[k], &cc[k]->key, sizeof cc[k]->key) != 0;
    for (int i = 0; i < N_BUF && s == VV_OK; i++) {
        const VkDeviceSize before = st->buf[i].buf ? st->buf[i].size : 0;
        s = ensure_buffer(
            st, &st->buf[i], sizes[i],
            (i == B_UBO ? VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT : VK_BUFFER_USAGE_STORAGE_BUFFER_BIT) |
                (i < B_RGBA ? dst : VK_BUFFER_USAGE_TRANSFER_SRC_BIT),
            0);
        /* a buffer made anew (larger) holds nothing yet */
        mm_up |= i == B_MM && st->buf[i].size != before;
        dist_up |= i == B_DIST && st->buf[i].size != before;
    }
    if (s == VV_OK)
        s = ensure_buffer(st, &st->readback, npx * 24, dst, 1);
    if (s == VV_OK)
        s = vv_vk_begin(vk);
    VkDeviceSize used = total;
    VkDeviceSize sent = 0, grow = 0; /* arrays sent; bytes the brick gains */
    if (s == VV_OK) {
        vv_vk_timestamp(vk, 0);
        /* the frame's data, then the images that changed: each channel's values
         * and gradient codes (stand-ins for the channels there are not), the
         * gradient magnitudes of a 2-D transfer function; the staging buffer
         * is made large enough for all of it before anything is recorded */
        VkDeviceSize need = total;
        for (int dry = 1; dry >= 0 && s == VV_OK; dry--) {
            if (!dry && brick) {
                /* room for it: the least recently used bricks out; the
                 * whole volume's images (a frame before) go too */
                brick_trim(st, brick, grow);
                static const int whole[3] = {I_VALUES, I_NORMALS, I_GMAG};
                for (int i = 0; i < 3; i++)
                    if (st->from[whole[i]].made && st->from[whole[i]].data) {
                        vv_vk_image_free(vk, &st->img[whole[i]]);
                        st->from[whole[i]].made = 0;
                    }
            }
            if (!dry)
                s = ensure_buffer(st, &st->staging, need, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, 1);
            VkDeviceSize *at = dry ? &need : &used;
            for (int k = 0; k < GPU_MAX_CH && s == VV_OK; k++) {
                if (k == 0 && brick) {
                    s = upload_brick(st, brick, cc[0], 0, 1, at, dry, &sent, &grow);
                    if (s == VV_OK)
                        s = upload_brick(st, brick, cc[0], 1, cc[0]->nrm != NULL, at, dry, &sent,
                                         &grow);
                    continue;
                }
                s = upload_image(st, I_VALUES + 2 * k, k < nch ? cc[k] : NULL, 0, at, dry, &sent);
                if (s == VV_OK)
                    s = upload_image(st, I_NORMALS + 2 * k, k < nch ? cc[k] : NULL, 1, at, dry,
                                     &sent);
            }
            if (s == VV_OK && brick)
                s = upload_brick(st, brick, c, 2, lut2d != NULL, at, dry, &sent, &grow);
            else if (s == VV_OK)
                s = upload_image(st, I_GMAG, lut2d ? c : NULL, 2, at, dry, &sent);
        }
    }
    if (s == VV_OK) {
        unsigned char *m = st->staging.map;
        memcpy(m + offs[B_UBO], &u, sizeof u);
        memset(m + offs[B_LUT], 0, sizes[B_LUT]);
        for (int k = 0; k < nch; k++)
            if (tabs[k].lut)
                memcpy(m + offs[B_LUT] + (size_t)k * VV_VC_LUT * 16, tabs[k].lut,
                       (size_t)VV_VC_LUT * 16);
        if (c && obj->shading)
            memcpy(m + offs[B_SPEC], sh.spec, sizes[B_SPEC]);
        else
            memset(m + offs[B_SPEC], 0, sizes[B_SPEC]);
        if (lut2d)
            memcpy(m + offs[B_LUT2], lut2d, sizes[B_LUT2]);
        else
            memset(m + offs[B_LUT2], 0, sizes[B_LUT2]);
        if (dist_up) {
            memset(m + offs[B_DIST], 0, sizes[B_DIST]);
            for (int k = 0; k < nch; k++)
                if (tabs[k].bdist)
                    memcpy(m + offs[B_DIST] + (size_t)k * nblocks, tabs[k].bdist, nblocks);
        }
        if (mm_up) {
            float *mm = (float *)(m + offs[B_MM]);
#pragma omp parallel for schedule(static) if (nblocks > 65536)
            for (size_t b = 0; b < nblocks; b++) {
                mm[2 * b] = c ? c->bmin[b] : 0;
                mm[2 * b + 1] = c ? c->bmax[b] : 0;
            }
        }
        /* the opacity in front, of the rows dispatched alone */
        const size_t px0 = (size_t)row0 * (size_t)view->width,
                     px1 = (size_t)row1 * (size_t)view->width;
        if (front) {
            float *fa = (float *)(m + offs[B_FRONT]);
            for (size_t i = px0; i < px1; i++)
                fa[i] = front->rgba[4 * i + 3];
        }
        VkBufferCopy cp[B_RGBA];
        for (int i = 0; i < B_RGBA; i++) {
            if ((i == B_DIST && !dist_up) || (i == B_MM && !mm_up) ||
                (i == B_FRONT && (!front || px1 == px0)))
                continue;
            cp[i] = (VkBufferCopy){.srcOffset = offs[i], .dstOffset = 0, .size = sizes[i]};
            if (i == B_FRONT)
                cp[i] = (VkBufferCopy){
                    .srcOffset = offs[i] + 4 * px0, .dstOffset = 4 * px0, .size = 4 * (px1 - px0)};
            vk->f.vkCmdCopyBuffer(vk->cmd, st->staging.buf, st->buf[i].buf, 1, &cp[i]);
        }
        vv_vk_barrier(vk, 0);

        VkDescriptorBufferInfo bi[N_BUF];
        VkWriteDescriptorSet wr[N_BUF + N_IMG];
        for (int i = 0; i < N_BUF; i++) {
            bi[i] = (VkDescriptorBufferInfo){st->buf[i].buf, 0, sizes[i]};
            wr[i] = (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
                                           .dstSet = st->set,
                                           .dstBinding = (uint32_t)binding_of[i],
                                           .descriptorCount = 1,
                                           .descriptorType =
                                               i == B_UBO ? VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER
                                                          : VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                           .pBufferInfo = &bi[i]};
        }
        VkDescriptorImageInfo ii[N_IMG];
        int nw = N_BUF;
        for (int i = 0; i < N_IMG; i++) {
            /* a cached brick's images stand for channel 0's and the magnitudes */
            const vv_vk_image *im = !brick           ? &st->img[i]
                                    : i == I_VALUES  ? &brick->img[0]
                                    : i == I_NORMALS ? &brick->img[1]
                                    : i == I_GMAG    ? &brick->img[2]
                                                     : &st->img[i];
            ii[i] = (VkDescriptorImageInfo){st->sampler, im->view,
                                            VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
            wr[nw++] =
                (VkWriteDescriptorSet){.sType = VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET,
                                       .dstSet = st->set,
                                       .dstBinding = (uint32_t)image_binding[i],
                                       .descriptorCount = 1,
                                       .descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                                       .pImageInfo = &ii[i]};
        }
        if (s == VV_OK) {
            vk->f.vkUpdateDescriptorSets(vk->dev, (uint32_t)nw, wr, 0, NULL);
            vk->f.vkCmdBindPipeline(vk->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, st->pipe);
            vk->f.vkCmdBindDescriptorSets(vk->cmd, VK_PIPELINE_BIND_POINT_COMPUTE, st->layout, 0, 1,
                                          &st->set, 0, NULL);
            const size_t n = px1 - px0; /* the pixels of the rows dispatched */
            if (n > 0) {
                vk->f.vkCmdDispatch(vk->cmd, (uint32_t)(col1 - col0 + 7) / 8,
                                    (uint32_t)(row1 - row0 + 7) / 8, 1);
                vv_vk_barrier(vk, 1);
                const VkBufferCopy back[3] = {{px0 * 16, px0 * 16, n * 16},
                                              {px0 * 4, npx * 16 + px0 * 4, n * 4},
                                              {px0 * 4, npx * 20 + px0 * 4, n * 4}};
                vk->f.vkCmdCopyBuffer(vk->cmd, st->buf[B_RGBA].buf, st->readback.buf, 1, &back[0]);
                vk->f.vkCmdCopyBuffer(vk->cmd, st->buf[B_DEPTH].buf, st->readback.buf, 1, &back[1]);
                if (key)
                    vk->f.vkCmdCopyBuffer(vk->cmd, st->buf[B_KEY].buf, st->readback.buf, 1,
                                          &back[2]);
            }
            vv_vk_timestamp(vk, 1);
            double ms = 0;
            s = vv_vk_submit_wait(vk, &ms);
            if (s == VV_OK) {
                /* what the subvolume buffers now hold (tables borrowed from
                 * their caches are known by their keys; tables built for
                 * this frame alone go up again next time) */
                st->mm_vol = c ? c->vol : NULL;
                st->mm_modified = c ? c->modified : 0;
                st->mm_blocks = nblocks;
                st->dist_n = nch;
                for (int k = 0; k < nch; k++) {
                    st->dist_vol[k] = owns[k] ? NULL : cc[k]->vol;
                    st->dist_modified[k] = cc[k]->modified;
                    st->dist_key[k] = cc[k]->key;
                }
                copy_back(out, key, st->readback.map, npx, px0, px1, col0, col1,
                          opt ? opt->threads : 0);
                if (opt && opt->stats) {
                    /* atomic: the multiresolution driver's clones add to one struct */
                    vv_render_stats *rs = opt->stats;
                    rs->device_ms += ms;
                    __atomic_fetch_add(&rs->upload_bytes, (uint64_t)sent, __ATOMIC_RELAXED);
                    /* a region of named voxels: a hit when the cache held
                     * them all, else (the cache off too) a miss */
                    if (rg && rg->from)
                        __atomic_fetch_add(brick && !grow ? &rs->cache_hits : &rs->cache_misses, 1u,
                                           __ATOMIC_RELAXED);
                }
            } else {
                /* a device that failed a frame is opened afresh next time */
                release_device(st);
            }
        } else {
            vk->f.vkEndCommandBuffer(vk->cmd);
        }
    } else if (vk->dev && s != VV_OK) {
        vk->f.vkEndCommandBuffer(vk->cmd);
    }
    /* a brick whose copies were recorded but never ran holds nothing */
    for (int i = 0; s != VV_OK && brick && i < st->n_bricks; i++)
        if (st->bricks[i] == brick)
            brick_evict(st, i);
    for (int k = 0; k < nch; k++)
        if (owns[k])
            vv_vtables_free(&tabs[k]);
    if (s == VV_OK && opt && opt->progress.fn && opt->progress.fn(opt->progress.user, 1.0))
        s = vv_error_set(VV_ERR_CANCELLED, "the gpu renderer: cancelled");
    vv_vcache_set_prune(&st->vc, w);
    return s;
}

/* ---- volumes over the device's memory: brick by brick ---------------------- */

/* The brick view of an in-memory volume in cubes of st->bricks_side cells
 * (vv_brick_source; the drivers' out-of-core path draws it). */
static const vv_volume *
pb_header(void *user) {
    return ((gpu_state *)user)->bricks_vol;
}

static void
pb_grid(void *user, int nb[3]) {
    memcpy(nb, ((gpu_state *)user)->bricks_nb, 3 * sizeof(int));
}

static void
pb_box(const gpu_state *st, int index, vv_brick_info *out) {
    const int *nb = st->bricks_nb, n = st->bricks_side;
    const int ix[3] = {index % nb[0], index / nb[0] % nb[1], index / (nb[0] * nb[1])};
    for (int a = 0; a < 3; a++) {
        const int last = st->bricks_vol->dims[a] - 1;
        out->lo[a] = ix[a] * n;
        out->hi[a] = out->lo[a] + n < last ? out->lo[a] + n : last;
        out->slo[a] = out->lo[a] > 0 ? out->lo[a] - 1 : 0;
        out->shi[a] = out->hi[a] < last ? out->hi[a] + 1 : last;
    }
}

static void
pb_info(void *user, int index, vv_brick_info *out) {
    const gpu_state *st = user;
    memset(out, 0, sizeof *out);
    pb_box(st, index, out);
    out->vmin = st->bricks_mm[2 * index];
    out->vmax = st->bricks_mm[2 * index + 1];
}

static vv_status
pb_load(void *user, int index, vv_volume **out) {
    gpu_state *st = user;
    vv_brick_info b;
    pb_box(st, index, &b);
    return vv_source_read_box(st->bricks_src, 0, b.slo, b.shi, out);
}

/* The bricks of @p v, cubes of @p side cells, and their min/max (the voxels
 * each reads), kept while @p v is unchanged. Errors: VV_ERR_NOMEM. */
static vv_status
prepare_bricks(gpu_state *st, vv_volume *v, int side) {
    if (st->bricks_vol == v && st->bricks_modified == v->modified && st->bricks_side == side)
        return VV_OK;
    free(st->bricks_mm);
    st->bricks_mm = NULL;
    vv_source_free(st->bricks_src);
    st->bricks_src = NULL;
    st->bricks_vol = NULL;
    size_t n = 1;
    for (int a = 0; a < 3; a++) {
        st->bricks_nb[a] = v->dims[a] > 1 ? (v->dims[a] - 2) / side + 1 : 1;
        n *= (size_t)st->bricks_nb[a];
    }
    st->bricks_side = side;
    st->bricks_mm = malloc(2 * n * sizeof(float));
    if (!st->bricks_mm)
        return vv_error_set(VV_ERR_NOMEM, "gpu: out of memory (%zu bricks)", n);
    vv_status s = vv_source_new_memory(&st->bricks_src, v); /* a reference of its own */
    if (s != VV_OK)
        return s;
    st->bricks_vol = v; /* for pb_box */
#pragma omp parallel for schedule(dynamic)
    for (long i = 0; i < (long)n; i++) {
        vv_brick_info b;
        pb_box(st, (int)i, &b);
        double lo = INFINITY, hi = -INFINITY;
        for (int z = b.slo[2]; z <= b.shi[2]; z++)
            for (int y = b.slo[1]; y <= b.shi[1]; y++) {
                const size_t row =
                    ((size_t)z * (size_t)v->dims[1] + (size_t)y) * (size_t)v->dims[0];
                for (int x = b.slo[0]; x <= b.shi[0]; x++) {
                    const double x0 = vv_voxel_value(v->type, v->data, row + (size_t)x);
                    lo = x0 < lo ? x0 : lo;
                    hi = x0 > hi ? x0 : hi;
                }
            }
        st->bricks_mm[2 * i] = (float)lo;
        st->bricks_mm[2 * i + 1] = (float)hi;
    }
    st->bricks_modified = v->modified;
    return VV_OK;
}

/* The side of the bricks @p obj is drawn in, or 0 when its volume fits the
 * device whole: its images (values as 16-bit or float, gradient codes,
 * gradient magnitudes) against the budget (option device_memory_mb; auto:
 * three quarters of the device's largest memory heap), and each side
 * against the device's 3-D image side. */
static int
brick_side(const gpu_state *st, const vv_object *obj) {
    const vv_volume *v = obj->volume;
    const double per_voxel = (vv_voxel_type_size(v->type) <= 2 ? 2 : 4) + 2.0 + 4.0;
    const double budget = device_budget(st);
    const uint32_t lim = st->vk.props.limits.maxImageDimension3D;
    int over = 0;
    for (int a = 0; a < 3; a++)
        over |= (uint32_t)v->dims[a] > lim;
    const double voxels = (double)v->dims[0] * v->dims[1] * v->dims[2];
    if (!over && (budget <= 0 || voxels * per_voxel <= budget))
        return 0;
    /* the largest power-of-two cube a quarter of the budget holds, within
     * the image side: bricks of 32 .. 1024 cells */
    int side = 1024;
    while (side > 32 &&
           ((double)side * side * side * per_voxel > 0.25 * budget || (uint32_t)side + 3 > lim))
        side /= 2;
    return side;
}

static vv_status
gpu_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
           vv_image *out) {
    gpu_state *st = state;
    const vv_object *obj;
    vv_status s = find_object(w, &obj);
    if (s == VV_OK && obj)
        s = open_device(st);
    const int side = s == VV_OK && obj && obj->n_channels < 2 ? brick_side(st, obj) : 0;
    if (s != VV_OK || !side)
        return s != VV_OK ? s : render_frame(st, w, view, opt, NULL, out, NULL);
    /* over the device's memory: brick by brick through the region contract
     * (gpu_render_region, on this state: one region on the device at a
     * time), by the brick driver as every renderer's out-of-core volumes */
    int object = 0;
    while (w->objects[object] != obj)
        object++;
    if ((s = prepare_bricks(st, obj->volume, side)) != VV_OK)
        return s;
    const vv_brick_source src = {.version = VV_BRICK_SOURCE_VERSION,
                                 .user = st,
                                 .header = pb_header,
                                 .grid = pb_grid,
                                 .info = pb_info,
                                 .load = pb_load};
    const drv_renderer self = {.ops = &vv_gpu_ops, .state = st};
    return drv_render_bricks(&self, w, object, &src, view, opt, out);
}

/* The region contract: a frame of the region's World
 * (vv_region_render_by_frame, as the ray caster's); the out-of-core
 * drivers page bricks through it, one region on the device at a time. */
static vv_status
gpu_render_region(void *state, const vv_world *w, const vv_view *view,
                  const vv_render_region *region, const vv_render_options *opt,
                  vv_region_image *out) {
    return vv_region_render_by_frame(render_frame, state, &((gpu_state *)state)->xray, w, view,
                                     region, opt, out);
}

#else /* !VV_HAVE_VULKAN */

static vv_status
gpu_render(void *state, const vv_world *w, const vv_view *view, const vv_render_options *opt,
           vv_image *out) {
    (void)state;
    (void)w;
    (void)view;
    (void)opt;
    (void)out;
    const char *why;
    vv_gpu_devices(NULL, 0, &why);
    return vv_error_set(VV_ERR_UNSUPPORTED, "%s", why);
}

#endif

static vv_status
gpu_init(void *state) {
    gpu_state *st = state;
    vv_vcache_set_init(&st->vc);
    return VV_OK;
}

static void
gpu_release(void *state) {
    gpu_state *st = state;
#if VV_HAVE_VULKAN
    release_device(st);
    free(st->bricks_mm);
    st->bricks_mm = NULL;
    vv_source_free(st->bricks_src);
    st->bricks_src = NULL;
    st->bricks_vol = NULL;
#endif
    vv_vcache_set_clear(&st->vc);
}

/* device: the context goes, and the next frame opens the device named. */
static vv_status
gpu_device_changed(void *state, const vv_option_spec *spec, const vv_option_value *v) {
    (void)spec;
    (void)v;
#if VV_HAVE_VULKAN
    gpu_state *st = state;
    release_device(st);
#else
    (void)state;
#endif
    return VV_OK;
}

static const char *const gpu_auto[] = {"auto", NULL};

#if VV_HAVE_VULKAN
/* out of core by bricks and under MPI; channels (up to GPU_MAX_CH, in memory);
 * its regions drawn in turn on its own device (the brick cache) */
#define GPU_CAPS (VV_RENDERER_REGION | VV_RENDERER_CHANNELS | VV_RENDERER_DEVICE)
#else
#define GPU_CAPS 0
#endif

/* The gpu renderer's options (docs/rendering.md, "GPU ray casting"). */
static const vv_option_spec gpu_options[] = {
    {"device", VV_OPTION_INT, "auto", 0, 15, 0, gpu_auto,
     "the Vulkan device to run on, by its number in `volvis renderers` (auto: the first GPU, "
     "else the first device, such as Mesa's lavapipe)",
     VV_OPTION_BIND_WORDS(gpu_state, device, INT, VV_OPTION_WORD_VALUES(-1), gpu_device_changed)},
    {"early_termination", VV_OPTION_REAL, "0.99", 0, 1, VV_OPTION_MIN_OPEN, NULL,
     "accumulated opacity that ends a composite ray",
     VV_OPTION_BIND(gpu_state, early_termination, DOUBLE)},
    {"device_memory_mb", VV_OPTION_REAL, "auto", 0, INFINITY, 0, gpu_auto,
     "MiB of the device's memory a volume may take whole (its values, gradients and gradient "
     "magnitudes); a larger one is drawn brick by brick; and the brick cache's budget: bricks "
     "drawn (out of core, or of such a volume) stay on the device between frames within it, "
     "least recently used out (auto: three quarters of the device's memory; 0: no limit)",
     VV_OPTION_BIND_WORDS(gpu_state, budget_mb, DOUBLE, VV_OPTION_WORD_VALUES(-1), NULL)},
    {"brick_cache", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "keep drawn bricks on the device between frames (0: upload each brick each time it is "
     "drawn; same image)",
     VV_OPTION_BIND(gpu_state, brick_cache, INT)},
    {"empty_space_skipping", VV_OPTION_BOOL, "1", 0, 1, 0, NULL,
     "leap over subvolumes the transfer function hides (0 for tests; same image)",
     VV_OPTION_BIND(gpu_state, skipping, INT)},
};

const vv_renderer_ops vv_gpu_ops = {
    .version = VV_RENDERER_OPS_VERSION,
    .info =
        {
            .name = "gpu",
            .description = "direct volume ray casting on a Vulkan device (a GPU, or lavapipe): "
                           "composite, mip, minip, xray, iso, attenuated-mip; one volume object of "
                           "up to 4 channels",
            .draws = VV_DRAWS(VV_OBJECT_VOLUME),
            .modes = VV_MODES_ALL | VV_MODE_BIT(VV_MODE_ATTENUATED_MIP),
            .caps = GPU_CAPS,
            .quality = "every quality casts one ray a pixel at the objects' step",
            .options = gpu_options,
            .n_options = VV_OPTIONS_COUNT(gpu_options),
        },
    .state_size = sizeof(gpu_state),
    .init = gpu_init,
    .release = gpu_release,
    .render = gpu_render,
#if VV_HAVE_VULKAN
    .render_region = gpu_render_region,
#endif
};
