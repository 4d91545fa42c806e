/*
 * The memory budget (include/volvis/core.h): the most bytes one reader or
 * decoder may allocate for one object. The default is computed once from
 * /proc/meminfo (half of MemAvailable) or the VOLVIS_MAX_MEMORY variable.
 */
#include <ctype.h>
#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/internal.h"
#include "volvis/core.h"

#define BUDGET_MIN ((uint64_t)64 << 20)
#define BUDGET_UNKNOWN ((uint64_t)4 << 30)

static _Atomic uint64_t budget; /* 0: not computed yet */

/* Half of MemAvailable, or 0 when /proc/meminfo cannot say. */
static uint64_t
half_available(void) {
    FILE *f = fopen("/proc/meminfo", "r");
    if (!f)
        return 0;
    char line[256];
    unsigned long long kb = 0;
    while (fgets(line, sizeof line, f))
        if (sscanf(line, "MemAvailable: %llu kB", &kb) == 1)
            break;
    fclose(f);
    return (uint64_t)kb * 1024 / 2;
}

static uint64_t
default_budget(void) {
    uint64_t b = 0;
    const char *env = getenv("VOLVIS_MAX_MEMORY");
    if (!env || !*env || vv_memory_size_parse(env, &b) != VV_OK || b == 0) {
        b = half_available();
        if (b == 0)
            b = BUDGET_UNKNOWN;
    }
    return b < BUDGET_MIN ? BUDGET_MIN : b;
}

void
vv_memory_budget_set(uint64_t bytes) {
    atomic_store(&budget, bytes ? bytes : default_budget());
}

uint64_t
vv_memory_budget_get(void) {
    uint64_t b = atomic_load(&budget);
    if (b == 0) {
        uint64_t zero = 0;
        b = default_budget();
        if (!atomic_compare_exchange_strong(&budget, &zero, b))
            b = zero; /* another thread set it first */
    }
    return b;
}

vv_status
vv_memory_budget_check(uint64_t bytes, const char *what) {
    uint64_t b = vv_memory_budget_get();
    if (bytes <= b)
        return VV_OK;
    return vv_error_set(VV_ERR_LIMIT,
                        "%s: %llu bytes is over the memory budget of %llu bytes (raise it with "
                        "--max-memory or VOLVIS_MAX_MEMORY)",
                        what ? what : "allocation", (unsigned long long)bytes,
                        (unsigned long long)b);
}

vv_status
vv_memory_size_parse(const char *text, uint64_t *out) {
    if (!text || !out)
        return vv_error_set(VV_ERR_INVALID, "memory size: NULL argument");
    const char *p = text;
    while (isspace((unsigned char)*p))
        p++;
    if (!isdigit((unsigned char)*p) && *p != '.')
        return vv_error_set(VV_ERR_INVALID, "memory size '%s': expected a number", text);
    errno = 0;
    char *end = NULL;
    double v = strtod(p, &end);
    if (errno || end == p || !(v >= 0))
        return vv_error_set(VV_ERR_INVALID, "memory size '%s': expected a number", text);
    double mul = 1;
    switch (toupper((unsigned char)*end)) {
    case 'K':
        mul = 1024.0;
        break;
    case 'M':
        mul = 1024.0 * 1024;
        break;
    case 'G':
        mul = 1024.0 * 1024 * 1024;
        break;
    case 'T':
        mul = 1024.0 * 1024 * 1024 * 1024;
        break;
    case 'B':
    case '\0':
        break;
    default:
        return vv_error_set(VV_ERR_INVALID, "memory size '%s': unknown unit (K, M, G or T)", text);
    }
    if (mul > 1) {
        end++;
        if (toupper((unsigned char)end[0]) == 'I' && toupper((unsigned char)end[1]) == 'B')
            end += 2;
        else if (toupper((unsigned char)end[0]) == 'B')
            end++;
    } else if (toupper((unsigned char)*end) == 'B') {
        end++;
    }
    if (*end != '\0')
        return vv_error_set(VV_ERR_INVALID, "memory size '%s': unknown unit (K, M, G or T)", text);
    double bytes = v * mul;
    if (bytes >= 18446744073709551615.0)
        return vv_error_set(VV_ERR_INVALID, "memory size '%s' is too large", text);
    *out = (uint64_t)bytes;
    return VV_OK;
}
