/*
 * The Vulkan side of the GPU renderer (vk.h): the loader opened at run
 * time, the device list, a compute context, buffers and 3-D images.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "render/gpu/vk.h"
#include "volvis/render.h"

#if VV_HAVE_VULKAN
#include <dlfcn.h>
#include <pthread.h>

/* The process's one instance and its devices, opened on first use. */
static struct {
    pthread_once_t once;
    void *lib;
    PFN_vkGetInstanceProcAddr gipa;
    VkInstance inst;
    vv_vk_fns f; /* the instance-level entries */
    int n;
    VkPhysicalDevice phys[16];
    vv_gpu_device dev[16];
    const char *why;
    int validation; /* VK_LAYER_KHRONOS_validation enabled (VV_GPU_VALIDATION=1) */
} G = {.once = PTHREAD_ONCE_INIT};

/* Validation messages seen (VV_GPU_VALIDATION=1): printed to stderr and
 * counted, so that the tests can assert none. */
static int validation_messages;

int
vv_gpu_validation_messages(void) {
    return __atomic_load_n(&validation_messages, __ATOMIC_RELAXED);
}

static VKAPI_ATTR VkBool32 VKAPI_CALL
on_debug(VkDebugUtilsMessageSeverityFlagBitsEXT sev, VkDebugUtilsMessageTypeFlagsEXT type,
         const VkDebugUtilsMessengerCallbackDataEXT *data, void *user) {
    (void)type;
    (void)user;
    if (sev >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT) {
        __atomic_add_fetch(&validation_messages, 1, __ATOMIC_RELAXED);
        fprintf(stderr, "volvis gpu: validation: %s\n", data->pMessage);
    }
    return VK_FALSE;
}

static VkDebugUtilsMessengerEXT messenger;

static void
open_instance(void) {
    const char *names[] = {"libvulkan.so.1", "libvulkan.so"};
    for (int i = 0; i < 2 && !G.lib; i++)
        G.lib = dlopen(names[i], RTLD_NOW | RTLD_LOCAL);
    if (!G.lib) {
        G.why = "no Vulkan loader (libvulkan.so.1; Debian: libvulkan1)";
        return;
    }
    void *sym = dlsym(G.lib, "vkGetInstanceProcAddr");
    memcpy(&G.gipa, &sym, sizeof G.gipa); /* POSIX: a symbol's address as a function pointer */
    if (!G.gipa) {
        G.why = "the Vulkan loader has no vkGetInstanceProcAddr";
        return;
    }
    PFN_vkCreateInstance create = (PFN_vkCreateInstance)G.gipa(NULL, "vkCreateInstance");
    PFN_vkEnumerateInstanceLayerProperties layers =
        (PFN_vkEnumerateInstanceLayerProperties)G.gipa(NULL, "vkEnumerateInstanceLayerProperties");
    if (!create) {
        G.why = "the Vulkan loader has no vkCreateInstance";
        return;
    }
    const char *want = getenv("VV_GPU_VALIDATION");
    const char *layer = "VK_LAYER_KHRONOS_validation";
    const char *ext = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
    if (want && want[0] == '1' && layers) {
        uint32_t n = 0;
        layers(&n, NULL);
        VkLayerProperties *lp = calloc(n ? n : 1, sizeof *lp);
        if (lp && layers(&n, lp) == VK_SUCCESS)
            for (uint32_t i = 0; i < n; i++)
                G.validation |= strcmp(lp[i].layerName, layer) == 0;
        free(lp);
        if (!G.validation)
            fprintf(stderr,
                    "volvis gpu: VV_GPU_VALIDATION=1 but %s is not installed "
                    "(Debian: vulkan-validationlayers)\n",
                    layer);
    }
    const VkApplicationInfo app = {.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO,
                                   .pApplicationName = "VolVis",
                                   .pEngineName = "VolVis",
                                   .apiVersion = VK_API_VERSION_1_2};
    const VkInstanceCreateInfo ci = {.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO,
                                     .pApplicationInfo = &app,
                                     .enabledLayerCount = G.validation ? 1 : 0,
                                     .ppEnabledLayerNames = &layer,
                                     .enabledExtensionCount = G.validation ? 1 : 0,
                                     .ppEnabledExtensionNames = &ext};
    VkResult r = create(&ci, NULL, &G.inst);
    if (r != VK_SUCCESS) {
        G.why = r == VK_ERROR_INCOMPATIBLE_DRIVER ? "no Vulkan 1.2 driver (Debian: mesa-vulkan-"
                                                    "drivers for lavapipe, or a GPU's driver)"
                                                  : "the Vulkan instance could not be created";
        return;
    }
#define VV_VK_LOAD(name) G.f.name = (PFN_##name)G.gipa(G.inst, #name);
    VV_VK_INSTANCE_FNS(VV_VK_LOAD)
#undef VV_VK_LOAD
    if (G.validation) {
        PFN_vkCreateDebugUtilsMessengerEXT cm =
            (PFN_vkCreateDebugUtilsMessengerEXT)G.gipa(G.inst, "vkCreateDebugUtilsMessengerEXT");
        const VkDebugUtilsMessengerCreateInfoEXT mi = {
            .sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT,
            .messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT |
                               VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
            .messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                           VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
            .pfnUserCallback = on_debug};
        if (cm)
            cm(G.inst, &mi, NULL, &messenger);
    }
    uint32_t n = 16;
    r = G.f.vkEnumeratePhysicalDevices(G.inst, &n, G.phys);
    if (r != VK_SUCCESS && r != VK_INCOMPLETE) {
        G.why = "the Vulkan devices could not be listed";
        return;
    }
    for (uint32_t i = 0; i < n; i++) {
        VkPhysicalDeviceProperties p;
        G.f.vkGetPhysicalDeviceProperties(G.phys[i], &p);
        if (p.apiVersion < VK_API_VERSION_1_2)
            continue; /* compute needs what 1.2 guarantees */
        VkPhysicalDeviceMemoryProperties m;
        G.f.vkGetPhysicalDeviceMemoryProperties(G.phys[i], &m);
        vv_gpu_device *d = &G.dev[G.n];
        snprintf(d->name, sizeof d->name, "%s", p.deviceName);
        d->kind = p.deviceType == VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU     ? "discrete GPU"
                  : p.deviceType == VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU ? "integrated GPU"
                  : p.deviceType == VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU    ? "virtual GPU"
                  : p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU            ? "CPU"
                                                                           : "other";
        d->cpu = p.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
        d->api_version = p.apiVersion;
        for (uint32_t h = 0; h < m.memoryHeapCount; h++)
            if ((m.memoryHeaps[h].flags & VK_MEMORY_HEAP_DEVICE_LOCAL_BIT) &&
                m.memoryHeaps[h].size > d->memory_bytes)
                d->memory_bytes = m.memoryHeaps[h].size;
        G.phys[G.n++] = G.phys[i];
    }
    if (G.n == 0)
        G.why = "no Vulkan 1.2 device (Debian: mesa-vulkan-drivers for lavapipe, or a GPU's "
                "driver)";
}

/* The instance, its devices and the loader stay for the life of the
 * process (reachable from G): destroying them at exit would unload the
 * driver before leak checkers look, and they could no longer tell a
 * driver's own allocations (Mesa's lavapipe keeps some) from ours. */
static void
open_once(void) {
    open_instance();
}

int
vv_gpu_validation_enabled(void) {
    pthread_once(&G.once, open_once);
    return G.validation;
}

int
vv_gpu_devices(vv_gpu_device *out, int max, const char **why) {
    pthread_once(&G.once, open_once);
    for (int i = 0; i < G.n && i < max; i++)
        out[i] = G.dev[i];
    if (why)
        *why = G.n ? NULL : G.why;
    return G.n;
}

const char *
vv_vk_result_name(VkResult r) {
    switch (r) {
    case VK_SUCCESS:
        return "VK_SUCCESS";
    case VK_ERROR_OUT_OF_HOST_MEMORY:
        return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY:
        return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED:
        return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST:
        return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_FEATURE_NOT_PRESENT:
        return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_FORMAT_NOT_SUPPORTED:
        return "VK_ERROR_FORMAT_NOT_SUPPORTED";
    case VK_ERROR_TOO_MANY_OBJECTS:
        return "VK_ERROR_TOO_MANY_OBJECTS";
    case VK_TIMEOUT:
        return "VK_TIMEOUT";
    default:
        return "VK_ERROR (other)";
    }
}

vv_status
vv_vk_check(const vv_vk *vk, VkResult r, const char *what) {
    if (r == VK_SUCCESS)
        return VV_OK;
    const vv_status s = r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY
                            ? VV_ERR_NOMEM
                            : VV_ERR_UNSUPPORTED;
    return vv_error_set(s, "gpu device %d (%s): %s failed: %s", vk->index, vk->props.deviceName,
                        what, vv_vk_result_name(r));
}

#define VK_TRY(vk, call, what)                                                                     \
    do {                                                                                           \
        VkResult vk_r_ = (call);                                                                   \
        if (vk_r_ != VK_SUCCESS)                                                                   \
            return vv_vk_check((vk), vk_r_, (what));                                               \
    } while (0)

vv_status
vv_vk_open(vv_vk *vk, int index) {
    memset(vk, 0, sizeof *vk);
    const char *why;
    const int n = vv_gpu_devices(NULL, 0, &why);
    if (n == 0)
        return vv_error_set(VV_ERR_UNSUPPORTED, "%s", why);
    if (index >= n)
        return vv_error_set(VV_ERR_INVALID,
                            "no Vulkan device %d (%d found: volvis renderers lists "
                            "them)",
                            index, n);
    if (index < 0) {
        index = 0;
        for (int i = n - 1; i >= 0; i--)
            if (!G.dev[i].cpu)
                index = i;
    }
    vk->f = G.f;
    vk->index = index;
    vk->phys = G.phys[index];
    vk->f.vkGetPhysicalDeviceProperties(vk->phys, &vk->props);
    vk->f.vkGetPhysicalDeviceMemoryProperties(vk->phys, &vk->mem);
    uint32_t nq = 0;
    vk->f.vkGetPhysicalDeviceQueueFamilyProperties(vk->phys, &nq, NULL);
    VkQueueFamilyProperties qf[32];
    nq = nq > 32 ? 32 : nq;
    vk->f.vkGetPhysicalDeviceQueueFamilyProperties(vk->phys, &nq, qf);
    int fam = -1;
    for (uint32_t i = 0; i < nq && fam < 0; i++)
        if (qf[i].queueFlags & VK_QUEUE_COMPUTE_BIT)
            fam = (int)i;
    if (fam < 0)
        return vv_error_set(VV_ERR_UNSUPPORTED, "gpu device %d (%s): no compute queue", index,
                            vk->props.deviceName);
    vk->family = (uint32_t)fam;
    const float prio = 1.0f;
    const VkDeviceQueueCreateInfo qi = {.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO,
                                        .queueFamilyIndex = vk->family,
                                        .queueCount = 1,
                                        .pQueuePriorities = &prio};
    const VkDeviceCreateInfo di = {.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO,
                                   .queueCreateInfoCount = 1,
                                   .pQueueCreateInfos = &qi};
    VK_TRY(vk, vk->f.vkCreateDevice(vk->phys, &di, NULL, &vk->dev), "vkCreateDevice");
#define VV_VK_LOAD(name) vk->f.name = (PFN_##name)vk->f.vkGetDeviceProcAddr(vk->dev, #name);
    VV_VK_DEVICE_FNS(VV_VK_LOAD)
#undef VV_VK_LOAD
    vk->f.vkGetDeviceQueue(vk->dev, vk->family, 0, &vk->queue);
    const VkCommandPoolCreateInfo pi = {.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO,
                                        .flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT,
                                        .queueFamilyIndex = vk->family};
    VK_TRY(vk, vk->f.vkCreateCommandPool(vk->dev, &pi, NULL, &vk->pool), "vkCreateCommandPool");
    const VkCommandBufferAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO,
                                            .commandPool = vk->pool,
                                            .level = VK_COMMAND_BUFFER_LEVEL_PRIMARY,
                                            .commandBufferCount = 1};
    VK_TRY(vk, vk->f.vkAllocateCommandBuffers(vk->dev, &ai, &vk->cmd), "vkAllocateCommandBuffers");
    const VkFenceCreateInfo fi = {.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VK_TRY(vk, vk->f.vkCreateFence(vk->dev, &fi, NULL, &vk->fence), "vkCreateFence");
    if (qf[vk->family].timestampValidBits > 0 && vk->props.limits.timestampPeriod > 0) {
        const VkQueryPoolCreateInfo qpi = {.sType = VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO,
                                           .queryType = VK_QUERY_TYPE_TIMESTAMP,
                                           .queryCount = 2};
        if (vk->f.vkCreateQueryPool(vk->dev, &qpi, NULL, &vk->timer) != VK_SUCCESS)
            vk->timer = VK_NULL_HANDLE;
        vk->ns_per_tick = vk->props.limits.timestampPeriod;
    }
    return VV_OK;
}

void
vv_vk_close(vv_vk *vk) {
    if (!vk->dev)
        return;
    if (vk->timer)
        vk->f.vkDestroyQueryPool(vk->dev, vk->timer, NULL);
    if (vk->fence)
        vk->f.vkDestroyFence(vk->dev, vk->fence, NULL);
    if (vk->pool)
        vk->f.vkDestroyCommandPool(vk->dev, vk->pool, NULL);
    vk->f.vkDestroyDevice(vk->dev, NULL);
    memset(vk, 0, sizeof *vk);
}

/* A memory type of @p bits with @p want (and, for host memory, preferably cached). */
static int
memory_type(const vv_vk *vk, uint32_t bits, VkMemoryPropertyFlags want) {
    for (uint32_t i = 0; i < vk->mem.memoryTypeCount; i++)
        if ((bits & (1u << i)) && (vk->mem.memoryTypes[i].propertyFlags & want) == want)
            return (int)i;
    return -1;
}

static vv_status
allocate(vv_vk *vk, VkMemoryRequirements req, VkMemoryPropertyFlags want, VkDeviceMemory *out) {
    int t = -1;
    if (want & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)
        t = memory_type(vk, req.memoryTypeBits, want | VK_MEMORY_PROPERTY_HOST_CACHED_BIT);
    if (t < 0)
        t = memory_type(vk, req.memoryTypeBits, want);
    if (t < 0)
        return vv_error_set(VV_ERR_UNSUPPORTED, "gpu device %d (%s): no memory type for %s",
                            vk->index, vk->props.deviceName,
                            (want & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT) ? "host buffers"
                                                                         : "device buffers");
    const VkMemoryAllocateInfo ai = {.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO,
                                     .allocationSize = req.size,
                                     .memoryTypeIndex = (uint32_t)t};
    VkResult r = vk->f.vkAllocateMemory(vk->dev, &ai, NULL, out);
    if (r != VK_SUCCESS)
        return vv_error_set(VV_ERR_NOMEM, "gpu device %d (%s): %llu bytes of %s memory: %s",
                            vk->index, vk->props.deviceName, (unsigned long long)req.size,
                            (want & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT) ? "host" : "device",
                            vv_vk_result_name(r));
    return VV_OK;
}

vv_status
vv_vk_buffer_new(vv_vk *vk, VkDeviceSize size, VkBufferUsageFlags usage, int host,
                 vv_vk_buffer *out) {
    memset(out, 0, sizeof *out);
    const VkBufferCreateInfo bi = {.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO,
                                   .size = size ? size : 16,
                                   .usage = usage,
                                   .sharingMode = VK_SHARING_MODE_EXCLUSIVE};
    VK_TRY(vk, vk->f.vkCreateBuffer(vk->dev, &bi, NULL, &out->buf), "vkCreateBuffer");
    VkMemoryRequirements req;
    vk->f.vkGetBufferMemoryRequirements(vk->dev, out->buf, &req);
    vv_status s =
        allocate(vk, req,
                 host ? VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT
                      : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT,
                 &out->mem);
    if (s != VV_OK) {
        vv_vk_buffer_free(vk, out);
        return s;
    }
    vk->f.vkBindBufferMemory(vk->dev, out->buf, out->mem, 0);
    out->size = bi.size;
    if (host) {
        VkResult r = vk->f.vkMapMemory(vk->dev, out->mem, 0, VK_WHOLE_SIZE, 0, &out->map);
        if (r != VK_SUCCESS) {
            vv_vk_buffer_free(vk, out);
            return vv_vk_check(vk, r, "vkMapMemory");
        }
    }
    return VV_OK;
}

void
vv_vk_buffer_free(vv_vk *vk, vv_vk_buffer *b) {
    if (b->map)
        vk->f.vkUnmapMemory(vk->dev, b->mem);
    if (b->buf)
        vk->f.vkDestroyBuffer(vk->dev, b->buf, NULL);
    if (b->mem)
        vk->f.vkFreeMemory(vk->dev, b->mem, NULL);
    memset(b, 0, sizeof *b);
}

vv_status
vv_vk_image_new(vv_vk *vk, const int dims[3], VkFormat format, vv_vk_image *out) {
    memset(out, 0, sizeof *out);
    const uint32_t lim = vk->props.limits.maxImageDimension3D;
    for (int a = 0; a < 3; a++)
        if (dims[a] < 1 || (uint32_t)dims[a] > lim)
            return vv_error_set(VV_ERR_LIMIT,
                                "gpu device %d (%s): a %d x %d x %d volume is over its 3-D "
                                "image side of %u",
                                vk->index, vk->props.deviceName, dims[0], dims[1], dims[2], lim);
    VkFormatProperties fp;
    vk->f.vkGetPhysicalDeviceFormatProperties(vk->phys, format, &fp);
    if (!(fp.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT))
        return vv_error_set(VV_ERR_UNSUPPORTED, "gpu device %d (%s): cannot sample format %d",
                            vk->index, vk->props.deviceName, (int)format);
    const VkImageCreateInfo ii = {
        .sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO,
        .imageType = VK_IMAGE_TYPE_3D,
        .format = format,
        .extent = {(uint32_t)dims[0], (uint32_t)dims[1], (uint32_t)dims[2]},
        .mipLevels = 1,
        .arrayLayers = 1,
        .samples = VK_SAMPLE_COUNT_1_BIT,
        .tiling = VK_IMAGE_TILING_OPTIMAL,
        .usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
        .sharingMode = VK_SHARING_MODE_EXCLUSIVE,
        .initialLayout = VK_IMAGE_LAYOUT_UNDEFINED};
    VkResult r = vk->f.vkCreateImage(vk->dev, &ii, NULL, &out->img);
    if (r != VK_SUCCESS)
        return r == VK_ERROR_OUT_OF_DEVICE_MEMORY || r == VK_ERROR_OUT_OF_HOST_MEMORY
                   ? vv_vk_check(vk, r, "vkCreateImage")
                   : vv_error_set(VV_ERR_LIMIT, "gpu device %d (%s): a %d x %d x %d 3-D image: %s",
                                  vk->index, vk->props.deviceName, dims[0], dims[1], dims[2],
                                  vv_vk_result_name(r));
    VkMemoryRequirements req;
    vk->f.vkGetImageMemoryRequirements(vk->dev, out->img, &req);
    vv_status s = allocate(vk, req, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, &out->mem);
    if (s != VV_OK) {
        vv_vk_image_free(vk, out);
        return s;
    }
    vk->f.vkBindImageMemory(vk->dev, out->img, out->mem, 0);
    const VkImageViewCreateInfo vi = {.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO,
                                      .image = out->img,
                                      .viewType = VK_IMAGE_VIEW_TYPE_3D,
                                      .format = format,
                                      .subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}};
    r = vk->f.vkCreateImageView(vk->dev, &vi, NULL, &out->view);
    if (r != VK_SUCCESS) {
        vv_vk_image_free(vk, out);
        return vv_vk_check(vk, r, "vkCreateImageView");
    }
    out->format = format;
    memcpy(out->dims, dims, sizeof out->dims);
    return VV_OK;
}

void
vv_vk_image_free(vv_vk *vk, vv_vk_image *im) {
    if (im->view)
        vk->f.vkDestroyImageView(vk->dev, im->view, NULL);
    if (im->img)
        vk->f.vkDestroyImage(vk->dev, im->img, NULL);
    if (im->mem)
        vk->f.vkFreeMemory(vk->dev, im->mem, NULL);
    memset(im, 0, sizeof *im);
}

vv_status
vv_vk_begin(vv_vk *vk) {
    VK_TRY(vk, vk->f.vkResetCommandBuffer(vk->cmd, 0), "vkResetCommandBuffer");
    const VkCommandBufferBeginInfo bi = {.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO,
                                         .flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT};
    VK_TRY(vk, vk->f.vkBeginCommandBuffer(vk->cmd, &bi), "vkBeginCommandBuffer");
    return VV_OK;
}

void
vv_vk_timestamp(vv_vk *vk, int which) {
    if (!vk->timer)
        return;
    if (which == 0)
        vk->f.vkCmdResetQueryPool(vk->cmd, vk->timer, 0, 2);
    vk->f.vkCmdWriteTimestamp(vk->cmd,
                              which == 0 ? VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT
                                         : VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT,
                              vk->timer, (uint32_t)which);
}

vv_status
vv_vk_submit_wait(vv_vk *vk, double *device_ms) {
    VK_TRY(vk, vk->f.vkEndCommandBuffer(vk->cmd), "vkEndCommandBuffer");
    VK_TRY(vk, vk->f.vkResetFences(vk->dev, 1, &vk->fence), "vkResetFences");
    const VkSubmitInfo si = {.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO,
                             .commandBufferCount = 1,
                             .pCommandBuffers = &vk->cmd};
    VK_TRY(vk, vk->f.vkQueueSubmit(vk->queue, 1, &si, vk->fence), "vkQueueSubmit");
    /* a minute: a frame that takes longer has hung the device */
    VK_TRY(vk, vk->f.vkWaitForFences(vk->dev, 1, &vk->fence, VK_TRUE, 60000000000ull),
           "vkWaitForFences");
    if (device_ms) {
        *device_ms = 0;
        uint64_t ts[2];
        if (vk->timer &&
            vk->f.vkGetQueryPoolResults(vk->dev, vk->timer, 0, 2, sizeof ts, ts, sizeof ts[0],
                                        VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT) ==
                VK_SUCCESS &&
            ts[1] >= ts[0])
            *device_ms = (double)(ts[1] - ts[0]) * vk->ns_per_tick * 1e-6;
    }
    return VV_OK;
}

static void
image_layout(vv_vk *vk, VkImage img, VkImageLayout from, VkImageLayout to, VkAccessFlags src_a,
             VkAccessFlags dst_a, VkPipelineStageFlags src_s, VkPipelineStageFlags dst_s) {
    const VkImageMemoryBarrier b = {.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER,
                                    .srcAccessMask = src_a,
                                    .dstAccessMask = dst_a,
                                    .oldLayout = from,
                                    .newLayout = to,
                                    .srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                                    .dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED,
                                    .image = img,
                                    .subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}};
    vk->f.vkCmdPipelineBarrier(vk->cmd, src_s, dst_s, 0, 0, NULL, 0, NULL, 1, &b);
}

void
vv_vk_copy_to_image(vv_vk *vk, const vv_vk_buffer *src, VkDeviceSize src_off, vv_vk_image *im) {
    image_layout(vk, im->img, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 0,
                 VK_ACCESS_TRANSFER_WRITE_BIT, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT,
                 VK_PIPELINE_STAGE_TRANSFER_BIT);
    const VkBufferImageCopy c = {
        .bufferOffset = src_off,
        .imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1},
        .imageExtent = {(uint32_t)im->dims[0], (uint32_t)im->dims[1], (uint32_t)im->dims[2]}};
    vk->f.vkCmdCopyBufferToImage(vk->cmd, src->buf, im->img, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                                 1, &c);
    image_layout(vk, im->img, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                 VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, VK_ACCESS_TRANSFER_WRITE_BIT,
                 VK_ACCESS_SHADER_READ_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT,
                 VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT);
}

void
vv_vk_barrier(vv_vk *vk, int after_compute) {
    const VkMemoryBarrier b = {
        .sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER,
        .srcAccessMask = after_compute ? VK_ACCESS_SHADER_WRITE_BIT : VK_ACCESS_TRANSFER_WRITE_BIT,
        .dstAccessMask = after_compute ? VK_ACCESS_TRANSFER_READ_BIT : VK_ACCESS_SHADER_READ_BIT};
    vk->f.vkCmdPipelineBarrier(
        vk->cmd,
        after_compute ? VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT : VK_PIPELINE_STAGE_TRANSFER_BIT,
        after_compute ? VK_PIPELINE_STAGE_TRANSFER_BIT : VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1,
        &b, 0, NULL, 0, NULL);
}

#else /* !VV_HAVE_VULKAN */

int
vv_gpu_validation_messages(void) {
    return 0;
}

int
vv_gpu_validation_enabled(void) {
    return 0;
}

int
vv_gpu_devices(vv_gpu_device *out, int max, const char **why) {
    (void)out;
    (void)max;
    if (why)
        *why = "this VolVis was built without Vulkan (libvulkan-dev and glslc)";
    return 0;
}

#endif
