/*
 * CRC-32C (Castagnoli, polynomial 0x1EDC6F41, reflected 0x82F63B78): the
 * checksum of Zarr v3's crc32c codec (shard indexes), iSCSI and ext4. zlib
 * has only the IEEE CRC-32. Not installed.
 */
#ifndef VOLVIS_CORE_CRC32C_H
#define VOLVIS_CORE_CRC32C_H

#include <stddef.h>
#include <stdint.h>

/* The CRC-32C of @p n bytes at @p p continued from @p crc (0 to start):
 * vv_crc32c(0, "123456789", 9) == 0xE3069283. Table-driven (slicing by
 * eight), reentrant. */
uint32_t vv_crc32c(uint32_t crc, const void *p, size_t n);

#endif
