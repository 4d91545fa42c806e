/*
 * The Vulkan side of the GPU renderer (internal): the loader opened at run
 * time (dlopen of libvulkan.so.1, so that the library starts on a machine
 * without one and the renderer says so in one line), the devices found,
 * one compute context on a chosen device, buffers, 3-D images and the
 * compute pipeline of the ray caster's shader (SPIR-V embedded at build
 * time). Vulkan 1.2 compute only: no window, no surface.
 *
 * Thread-safety: the loader and the device list are opened once under a
 * lock; a context serves one thread at a time (the renderer's state owns
 * one).
 */
#ifndef VV_RENDER_GPU_VK_H
#define VV_RENDER_GPU_VK_H

#include <stddef.h>
#include <stdint.h>

#include "volvis/core.h"

#if VV_HAVE_VULKAN
#define VK_NO_PROTOTYPES
#include <vulkan/vulkan.h>

/* Every Vulkan call the renderer makes, loaded from the driver. */
#define VV_VK_INSTANCE_FNS(X)                                                                      \
    X(vkDestroyInstance)                                                                           \
    X(vkEnumeratePhysicalDevices)                                                                  \
    X(vkGetPhysicalDeviceProperties)                                                               \
    X(vkGetPhysicalDeviceQueueFamilyProperties)                                                    \
    X(vkGetPhysicalDeviceMemoryProperties)                                                         \
    X(vkGetPhysicalDeviceFormatProperties)                                                         \
    X(vkCreateDevice)                                                                              \
    X(vkGetDeviceProcAddr)
#define VV_VK_DEVICE_FNS(X)                                                                        \
    X(vkDestroyDevice)                                                                             \
    X(vkGetDeviceQueue)                                                                            \
    X(vkCreateBuffer)                                                                              \
    X(vkDestroyBuffer)                                                                             \
    X(vkGetBufferMemoryRequirements)                                                               \
    X(vkAllocateMemory)                                                                            \
    X(vkFreeMemory)                                                                                \
    X(vkBindBufferMemory)                                                                          \
    X(vkBindImageMemory)                                                                           \
    X(vkMapMemory)                                                                                 \
    X(vkUnmapMemory)                                                                               \
    X(vkCreateImage)                                                                               \
    X(vkDestroyImage)                                                                              \
    X(vkGetImageMemoryRequirements)                                                                \
    X(vkCreateImageView)                                                                           \
    X(vkDestroyImageView)                                                                          \
    X(vkCreateSampler)                                                                             \
    X(vkDestroySampler)                                                                            \
    X(vkCreateShaderModule)                                                                        \
    X(vkDestroyShaderModule)                                                                       \
    X(vkCreateDescriptorSetLayout)                                                                 \
    X(vkDestroyDescriptorSetLayout)                                                                \
    X(vkCreatePipelineLayout)                                                                      \
    X(vkDestroyPipelineLayout)                                                                     \
    X(vkCreateComputePipelines)                                                                    \
    X(vkDestroyPipeline)                                                                           \
    X(vkCreateDescriptorPool)                                                                      \
    X(vkDestroyDescriptorPool)                                                                     \
    X(vkAllocateDescriptorSets)                                                                    \
    X(vkUpdateDescriptorSets)                                                                      \
    X(vkCreateCommandPool)                                                                         \
    X(vkDestroyCommandPool)                                                                        \
    X(vkAllocateCommandBuffers)                                                                    \
    X(vkBeginCommandBuffer)                                                                        \
    X(vkEndCommandBuffer)                                                                          \
    X(vkResetCommandBuffer)                                                                        \
    X(vkCmdBindPipeline)                                                                           \
    X(vkCmdBindDescriptorSets)                                                                     \
    X(vkCmdDispatch)                                                                               \
    X(vkCmdCopyBuffer)                                                                             \
    X(vkCmdCopyBufferToImage)                                                                      \
    X(vkCmdPipelineBarrier)                                                                        \
    X(vkCmdResetQueryPool)                                                                         \
    X(vkCmdWriteTimestamp)                                                                         \
    X(vkCreateQueryPool)                                                                           \
    X(vkDestroyQueryPool)                                                                          \
    X(vkGetQueryPoolResults)                                                                       \
    X(vkCreateFence)                                                                               \
    X(vkDestroyFence)                                                                              \
    X(vkResetFences)                                                                               \
    X(vkWaitForFences)                                                                             \
    X(vkQueueSubmit)

#define VV_VK_DECLARE(name) PFN_##name name;
typedef struct vv_vk_fns {
    VV_VK_INSTANCE_FNS(VV_VK_DECLARE)
    VV_VK_DEVICE_FNS(VV_VK_DECLARE)
} vv_vk_fns;
#undef VV_VK_DECLARE

/* A buffer and its memory; map non-NULL for host-visible ones (mapped for life). */
typedef struct vv_vk_buffer {
    VkBuffer buf;
    VkDeviceMemory mem;
    VkDeviceSize size;
    void *map;
} vv_vk_buffer;

/* A 3-D image in device memory, sampled by texelFetch. */
typedef struct vv_vk_image {
    VkImage img;
    VkImageView view;
    VkDeviceMemory mem;
    VkFormat format;
    int dims[3];
} vv_vk_image;

/* One compute context: a device, its queue, a command buffer, a fence, a
 * timestamp pool. */
typedef struct vv_vk {
    vv_vk_fns f;
    VkPhysicalDevice phys;
    VkPhysicalDeviceProperties props;
    VkPhysicalDeviceMemoryProperties mem;
    VkDevice dev;
    VkQueue queue;
    uint32_t family;
    VkCommandPool pool;
    VkCommandBuffer cmd;
    VkFence fence;
    VkQueryPool timer; /* two timestamps, or VK_NULL_HANDLE where the queue has none */
    double ns_per_tick;
    int index; /* the device's number in vv_gpu_device_count's list */
} vv_vk;

/* Opens a context on device @p index (-1: the first real GPU, else the
 * first device). Errors: VV_ERR_UNSUPPORTED (no loader, no device, no
 * compute queue, a device that fails: the message names it). */
vv_status vv_vk_open(vv_vk *vk, int index);
/* Releases what vv_vk_open made (a zeroed context: nothing). */
void vv_vk_close(vv_vk *vk);

/* A buffer of @p size bytes: host-visible and mapped (@p host), else
 * device-local. Errors: VV_ERR_NOMEM (the device's memory), VV_ERR_UNSUPPORTED. */
vv_status vv_vk_buffer_new(vv_vk *vk, VkDeviceSize size, VkBufferUsageFlags usage, int host,
                           vv_vk_buffer *out);
void vv_vk_buffer_free(vv_vk *vk, vv_vk_buffer *b);

/* A sampled 3-D image of @p dims in @p format, device-local. Errors:
 * VV_ERR_LIMIT (over the device's 3-D image side), VV_ERR_UNSUPPORTED
 * (the format cannot be sampled), VV_ERR_NOMEM. */
vv_status vv_vk_image_new(vv_vk *vk, const int dims[3], VkFormat format, vv_vk_image *out);
void vv_vk_image_free(vv_vk *vk, vv_vk_image *im);

/* Begins recording the context's one command buffer. */
vv_status vv_vk_begin(vv_vk *vk);
/* Ends it, submits it and waits; *device_ms (may be NULL) gets the time
 * between the two timestamps written (vv_vk_timestamp), or 0. */
vv_status vv_vk_submit_wait(vv_vk *vk, double *device_ms);
/* Records timestamp @p which (0 start, 1 end; 0 also resets the pool). */
void vv_vk_timestamp(vv_vk *vk, int which);
/* Records a copy of @p bytes from @p src (a host buffer, at @p src_off) to
 * image @p im, with the layout transitions around it (the image ends ready
 * for compute shaders to read). */
void vv_vk_copy_to_image(vv_vk *vk, const vv_vk_buffer *src, VkDeviceSize src_off, vv_vk_image *im);
/* A barrier: transfer writes before compute reads, or (@p after_compute)
 * compute writes before transfer reads. */
void vv_vk_barrier(vv_vk *vk, int after_compute);
/* VV_OK for VK_SUCCESS, else a one-line library error naming the call
 * @p what and the device: VV_ERR_NOMEM for the out-of-memory results,
 * VV_ERR_UNSUPPORTED for the others. */
vv_status vv_vk_check(const vv_vk *vk, VkResult r, const char *what);
/* "VK_ERROR_..." of @p r. */
const char *vv_vk_result_name(VkResult r);
#endif /* VV_HAVE_VULKAN */

/* The warnings and errors the Vulkan validation layers reported in this
 * process: they are enabled when the environment has VV_GPU_VALIDATION=1
 * before the first Vulkan call (and Debian's vulkan-validationlayers is
 * installed), each printed to stderr; the tests assert none. Thread-safe. */
int vv_gpu_validation_messages(void);
/* 1 when the validation layers are on (VV_GPU_VALIDATION=1 and installed). */
int vv_gpu_validation_enabled(void);

#endif
