/* The volume writers' checks before a file is opened (write_check.h). */
#include "io/write_check.h"

#include <math.h>

#include "core/internal.h"

vv_status
io_write_check_voxels(const vv_volume *v, int has_data, int writable) {
    if (!has_data)
        return vv_error_set(VV_ERR_INVALID, "volume has no data");
    if (!writable)
        return vv_error_set(VV_ERR_UNSUPPORTED, "voxel type %d cannot be written", (int)v->type);
    return VV_OK;
}

vv_status
io_write_check_geometry(const vv_volume *v, unsigned flags) {
    for (int i = 0; i < 3; i++)
        if (!((flags & IO_WRITE_ANY_SPACING) || v->spacing[i] > 0) || !isfinite(v->spacing[i]) ||
            !isfinite(v->origin[i]))
            return vv_error_set(VV_ERR_INVALID, "axis %d: spacing %g, origin %g", i, v->spacing[i],
                                v->origin[i]);
    if (!(flags & IO_WRITE_NO_DIRECTION))
        for (int i = 0; i < 9; i++)
            if (!isfinite(v->direction[i]))
                return vv_error_set(VV_ERR_INVALID, "the direction matrix is not finite");
    return VV_OK;
}
