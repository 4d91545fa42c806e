/*
 * The memory budget (include/volvis/core.h): the most bytes one reader or
 * decoder may allocate for one object. The default is computed once: the
 * VOLVIS_MAX_MEMORY variable, else half of what the machine and the
 * process's memory cgroups still allow (MemAvailable in /proc/meminfo; each
 * cgroup's limit less its usage, page cache it can reclaim not counted: the
 * kernel's OOM killer acts on the cgroup, not on the machine).
 */
#include <ctype.h>
#include <errno.h>
#include <pthread.h>
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

/* The first unsigned number in the file @p dir/@p name ("max" and a
 * missing file: UINT64_MAX, no limit). */
static uint64_t
read_u64(const char *dir, const char *name) {
    char path[4096];
    if (snprintf(path, sizeof path, "%s/%s", dir, name) >= (int)sizeof path)
        return UINT64_MAX;
    FILE *f = fopen(path, "r");
    if (!f)
        return UINT64_MAX;
    unsigned long long v = 0;
    int ok = fscanf(f, "%llu", &v) == 1;
    fclose(f);
    return ok ? (uint64_t)v : UINT64_MAX;
}

/* The value of @p key in the memory.stat of @p dir, 0 when absent. */
static uint64_t
stat_u64(const char *dir, const char *key) {
    char path[4096];
    if (snprintf(path, sizeof path, "%s/memory.stat", dir) >= (int)sizeof path)
        return 0;
    FILE *f = fopen(path, "r");
    if (!f)
        return 0;
    char line[256];
    size_t n = strlen(key);
    unsigned long long v = 0;
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, key, n) && line[n] == ' ' && sscanf(line + n, "%llu", &v) == 1)
            break;
    fclose(f);
    return (uint64_t)v;
}

/*
 * Where the process's memory cgroup is: @p dir receives the folder of its
 * cgroup (the mount point joined with the path /proc/self/cgroup names,
 * less the mount's own root) and @p top the mount point. Version 1's memory
 * hierarchy when it is mounted (a hybrid system has the memory controller
 * there), else the unified version 2 hierarchy. Returns 1 for version 1, 2
 * for version 2, 0 when there is none.
 */
static int
memory_cgroup(char *dir, size_t dirlen, char *top, size_t toplen) {
    char line[4096], v1_mnt[1024] = "", v1_root[1024] = "", v2_mnt[1024] = "", v2_root[1024] = "";
    FILE *f = fopen("/proc/self/mountinfo", "r");
    if (!f)
        return 0;
    while (fgets(line, sizeof line, f)) {
        /* id parent major:minor root mount-point options [tags] - type source super-options */
        char root[1024], mnt[1024], type[64], super[1024];
        const char *dash = strstr(line, " - ");
        if (!dash || sscanf(line, "%*s %*s %*s %1023s %1023s", root, mnt) != 2 ||
            sscanf(dash + 3, "%63s %*s %1023s", type, super) != 2)
            continue;
        if (!strcmp(type, "cgroup2") && !v2_mnt[0]) {
            snprintf(v2_mnt, sizeof v2_mnt, "%s", mnt);
            snprintf(v2_root, sizeof v2_root, "%s", root);
        } else if (!strcmp(type, "cgroup") && !v1_mnt[0]) {
            char *save = NULL;
            for (char *t = strtok_r(super, ",", &save); t; t = strtok_r(NULL, ",", &save))
                if (!strcmp(t, "memory")) {
                    snprintf(v1_mnt, sizeof v1_mnt, "%s", mnt);
                    snprintf(v1_root, sizeof v1_root, "%s", root);
                }
        }
    }
    fclose(f);
    f = fopen("/proc/self/cgroup", "r");
    if (!f)
        return 0;
    char v1_path[2048] = "", v2_path[2048] = "";
    int have_v1 = 0, have_v2 = 0;
    while (fgets(line, sizeof line, f)) {
        line[strcspn(line, "\n")] = '\0';
        char *c1 = strchr(line, ':');
        char *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
        if (!c2)
            continue;
        *c2 = '\0';
        const char *ctrls = c1 + 1, *path = c2 + 1;
        if (!strcmp(line, "0") && !*ctrls) {
            snprintf(v2_path, sizeof v2_path, "%s", path);
            have_v2 = 1;
        } else {
            char list[1024];
            snprintf(list, sizeof list, "%s", ctrls);
            char *save = NULL;
            for (char *t = strtok_r(list, ",", &save); t; t = strtok_r(NULL, ",", &save))
                if (!strcmp(t, "memory")) {
                    snprintf(v1_path, sizeof v1_path, "%s", path);
                    have_v1 = 1;
                }
        }
    }
    fclose(f);
    int version = have_v1 && v1_mnt[0] ? 1 : have_v2 && v2_mnt[0] ? 2 : 0;
    if (!version)
        return 0;
    const char *mnt = version == 1 ? v1_mnt : v2_mnt;
    const char *root = version == 1 ? v1_root : v2_root;
    const char *path = version == 1 ? v1_path : v2_path;
    size_t rl = strlen(root);
    /* a cgroup namespace mounts its own cgroup as the root: strip it */
    if (strcmp(root, "/") && !strncmp(path, root, rl) && (path[rl] == '/' || !path[rl]))
        path += rl;
    if (snprintf(dir, dirlen, "%s%s", mnt, strcmp(path, "/") ? path : "") >= (int)dirlen ||
        snprintf(top, toplen, "%s", mnt) >= (int)toplen)
        return 0;
    return version;
}

/*
 * What the memory cgroups of the process still allow: over its cgroup and
 * each ancestor up to the hierarchy's root, the least of limit less usage
 * (usage less the inactive page cache, which the kernel reclaims before it
 * kills). UINT64_MAX when no cgroup sets a limit.
 */
static char cg_dir[4096], cg_top[1024];
static int cg_version;
static pthread_once_t cg_once = PTHREAD_ONCE_INIT;

static void
cg_locate(void) {
    cg_version = memory_cgroup(cg_dir, sizeof cg_dir, cg_top, sizeof cg_top);
}

static uint64_t
cgroup_headroom(void) {
    /* where the cgroup is, found once (a process does not move in practice);
     * its limit and usage read each time */
    pthread_once(&cg_once, cg_locate);
    int version = cg_version;
    if (!version)
        return UINT64_MAX;
    char dir[4096], top[1024];
    memcpy(dir, cg_dir, sizeof dir);
    memcpy(top, cg_top, sizeof top);
    uint64_t least = UINT64_MAX;
    size_t tl = strlen(top);
    for (;;) {
        uint64_t limit = read_u64(dir, version == 1 ? "memory.limit_in_bytes" : "memory.max");
        /* version 1 writes "no limit" as a huge page-aligned number */
        if (limit < ((uint64_t)1 << 62)) {
            uint64_t usage =
                read_u64(dir, version == 1 ? "memory.usage_in_bytes" : "memory.current");
            if (usage == UINT64_MAX)
                usage = 0;
            uint64_t cache = stat_u64(dir, version == 1 ? "total_inactive_file" : "inactive_file");
            usage -= cache < usage ? cache : usage;
            uint64_t room = limit > usage ? limit - usage : 0;
            if (room < least)
                least = room;
        }
        char *slash = strrchr(dir, '/');
        if (strlen(dir) <= tl || !slash || (size_t)(slash - dir) < tl)
            break;
        *slash = '\0'; /* the parent cgroup */
    }
    return least;
}

int
vv_memory_cgroup_root(char *buf, size_t cap) {
    pthread_once(&cg_once, cg_locate);
    if (!cg_version || snprintf(buf, cap, "%s", cg_top) >= (int)cap)
        return 0;
    return 1;
}

uint64_t
vv_memory_available(void) {
    uint64_t avail = half_available() * 2;
    uint64_t room = cgroup_headroom();
    if (avail == 0)
        return room;
    return room < avail ? room : avail;
}

static uint64_t
default_budget(void) {
    uint64_t b = 0;
    const char *env = getenv("VOLVIS_MAX_MEMORY");
    if (!env || !*env || vv_memory_size_parse(env, &b) != VV_OK || b == 0) {
        b = half_available();
        uint64_t room = cgroup_headroom();
        if (room != UINT64_MAX && (b == 0 || room / 2 < b))
            b = room / 2;
        if (b == 0 && room == UINT64_MAX)
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
    if (bytes <= b) {
        /* a budget raised by hand still cannot pass a cgroup's limit: the
         * allocation would succeed and the OOM killer end the process
         * (objects under 16 MiB are not worth the files read) */
        if (bytes < ((uint64_t)16 << 20))
            return VV_OK;
        uint64_t room = cgroup_headroom();
        if (bytes <= room)
            return VV_OK;
        return vv_error_set(VV_ERR_LIMIT,
                            "%s: %llu bytes is more than the %llu bytes the memory cgroup's "
                            "limit leaves",
                            what ? what : "allocation", (unsigned long long)bytes,
                            (unsigned long long)room);
    }
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
