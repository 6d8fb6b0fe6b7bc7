/*
 * flags.c — texel flags counted by reason and drawn in a colour code (contract in transform.h, "flags").
 */
#include <string.h>

#include "mr_internal.h"
#include "transform.h"

/* spec2metal / metal2spec: a texel's most severe flag. */
static const mr_flag_colour workflow_colours[] = {
    {MR_WF_METHOD_FAILED, {1.0f, 0.0f, 0.0f}},   /* red */
    {MR_WF_NONFINITE_INPUT, {1.0f, 0.0f, 1.0f}}, /* magenta */
    {MR_WF_CLAMPED_INPUT, {0.0f, 0.5f, 1.0f}},   /* blue */
    {MR_WF_OFF_MANIFOLD, {1.0f, 0.5f, 0.0f}},    /* orange */
};
const mr_flag_code mr_workflow_flag_code = {MR_FLAG_PAINT_FIRST,
                                            (int)(sizeof workflow_colours / sizeof workflow_colours[0]),
                                            workflow_colours};

void mr_flags_count(const uint8_t *flags, size_t n, const unsigned *reasons, int reason_count, size_t *counts) {
    for (int r = 0; r < reason_count; r++) counts[r] = 0;
    if (flags == NULL) return;
    for (size_t i = 0; i < n; i++)
        for (int r = 0; r < reason_count; r++) counts[r] += (flags[i] & reasons[r]) != 0;
}

mr_status mr_flag_picture(const uint8_t *flags, int width, int height, const mr_flag_code *code, mr_image **out) {
    if (flags == NULL || code == NULL || out == NULL || (code->count > 0 && code->colours == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "mr_flag_picture: NULL argument");
    mr_image *picture = NULL;
    mr_status status = mr_image_create(width, height, 3, &picture); // zeroed: black
    if (status != MR_OK) return status;
    const size_t n = (size_t)width * (size_t)height;
    for (size_t i = 0; i < n; i++) {
        float *px = picture->pixels + 3 * i;
        for (int k = 0; k < code->count; k++) {
            const mr_flag_colour *c = &code->colours[k];
            if ((flags[i] & c->flags) == 0) continue;
            if (code->paint == MR_FLAG_PAINT_FIRST) {
                memcpy(px, c->rgb, sizeof c->rgb);
                break;
            }
            for (int ch = 0; ch < 3; ch++) px[ch] = px[ch] > c->rgb[ch] ? px[ch] : c->rgb[ch];
        }
    }
    *out = picture;
    return MR_OK;
}
