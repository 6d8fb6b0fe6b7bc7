/* cmd_ssim.c — `matremap ssim A B [--map OUT.png] [--exposure E] [--mask M] [--threads T] [--json]`: SSIM and
 * RMSE of two images, over the whole frame or over an object mask (metrics.h). */
#include <string.h>

#include "cli.h"

static void print_help(void) {
    printf("Usage: matremap ssim A B [--map OUT.png] [--exposure E] [--downsample] [--mask M] [--threads T]\n"
           "                         [--json]\n"
           "\n"
           "Prints the mean SSIM of images A and B (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5,\n"
           "K1 = 0.01, K2 = 0.03, L = 1) computed on display-referred luma: linear radiance times the\n"
           "exposure, clamped to [0,1], sRGB-encoded, Y' = 0.299 R' + 0.587 G' + 0.114 B' (docs/metrics.md).\n"
           "8-bit files are sRGB-decoded on read, so a PNG is compared on its own pixel values.\n"
           "With --json, prints {\"ssim\": ..., \"rmse\": ...} where RMSE is over linear RGB.\n"
           "\n"
           "With --mask M (the object's coverage, e.g. from 'matremap render --mask M': one channel, values in\n"
           "[0, 1], read linearly; a pixel > 0 is the object's), SSIM is averaged over the pixels whose 11x11\n"
           "window touches the object (the mask dilated by 5 pixels) and RMSE is taken over the object's pixels,\n"
           "also relative to A's mean over them (docs/metrics.md). The plain output is then the object's SSIM;\n"
           "--json adds \"object_ssim\", \"object_rmse\" and \"object_relative_rmse\" after the whole-frame\n"
           "\"ssim\" and \"rmse\".\n"
           "\n"
           "Options:\n"
           "  --map FILE      write the SSIM map as a false-colour picture (black = identical)\n"
           "  --exposure E    multiply linear values by E before the display mapping (default 1)\n"
           "  --downsample    apply Wang's MATLAB rule (box filter and decimate by round(min side/256));\n"
           "                  not with --mask\n"
           "  --mask M        also compare over the object whose coverage M holds (above)\n"
           "  --threads T     threads for the measures (default 0: automatic, all cores for images of at\n"
           "                  least 65536 pixels, one below); the figures do not depend on it\n"
           "  --json          machine-readable output\n"
           "  --help          this text\n");
}

int cmd_ssim(int argc, char **argv) {
    const char *paths[2] = {NULL, NULL};
    const char *map_path = NULL, *mask_path = NULL;
    int json = 0;
    mr_ssim_options opts = {0};
    opts.exposure = 1.0;
    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
        if ((taken = cli_take_option("ssim", argc, argv, &i, "--map", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            map_path = value;
        } else if ((taken = cli_take_option("ssim", argc, argv, &i, "--exposure", &value))) {
            if (taken < 0 || !cli_parse_double("ssim", "--exposure", value, 1e-9, 1e9, &opts.exposure))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("ssim", argc, argv, &i, "--mask", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            mask_path = value;
        } else if ((taken = cli_take_option("ssim", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("ssim", "--threads", value, 0, MR_METRICS_MAX_THREADS, &opts.threads))
                return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--downsample") == 0) {
            opts.downsample = 1;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            return cli_usage_error("ssim", "unknown option '%s'", argv[i]);
        } else if (paths[0] == NULL) {
            paths[0] = argv[i];
        } else if (paths[1] == NULL) {
            paths[1] = argv[i];
        } else {
            return cli_usage_error("ssim", "unexpected argument '%s' (give exactly two images)", argv[i]);
        }
    }
    if (paths[1] == NULL) return cli_usage_error("ssim", "expected two images A and B");
    if (mask_path != NULL && opts.downsample)
        return cli_usage_error("ssim", "--mask and --downsample cannot be combined (the mask is at full resolution)");

    mr_output_plan io = {0};
    mr_output_plan_inputf(&io, paths[0], "image A %s", paths[0]);
    mr_output_plan_inputf(&io, paths[1], "image B %s", paths[1]);
    if (mask_path != NULL) mr_output_plan_inputf(&io, mask_path, "--mask %s", mask_path);
    if (map_path != NULL) mr_output_plan_output(&io, map_path, "--map");
    int code = cli_plan_check("ssim", &io);
    mr_output_plan_free(&io);
    if (code != CLI_EXIT_OK) return code;

    mr_image *images[2] = {NULL, NULL};
    mr_image *map = NULL, *picture = NULL, *mask = NULL;
    double ssim = 0.0, rmse = 0.0, object_ssim = 0.0, object_rmse = 0.0, object_mean = 0.0;
    mr_status status = MR_OK;
    for (int k = 0; k < 2 && status == MR_OK; k++) status = mr_img_read(paths[k], NULL, &images[k]);
    if (status == MR_OK && (images[0]->width != images[1]->width || images[0]->height != images[1]->height)) {
        fprintf(stderr, "matremap ssim: error: '%s' is %dx%d but '%s' is %dx%d: images must have the same size\n",
                paths[0], images[0]->width, images[0]->height, paths[1], images[1]->width, images[1]->height);
        mr_image_free(images[0]);
        mr_image_free(images[1]);
        return CLI_EXIT_BAD_INPUT;
    }
    // Compare colour with colour: a grey image against an RGB(A) one is broadcast, alpha is ignored.
    for (int k = 0; k < 2 && status == MR_OK; k++) {
        if (images[k]->channels == 3) continue;
        mr_img_read_options ro = {0};
        ro.channels = 3;
        mr_image_free(images[k]);
        images[k] = NULL;
        status = mr_img_read(paths[k], &ro, &images[k]);
    }
    // Measurements: finite radiance >= 0, or exit 2 naming the file, the pixel and the value.
    for (int k = 0; k < 2 && status == MR_OK; k++) status = cli_check_radiance(images[k], paths[k]);
    if (status == MR_OK) status = mr_ssim(images[0], images[1], &opts, &ssim, map_path ? &map : NULL);
    if (status == MR_OK) status = mr_rmse_masked(images[0], images[1], NULL, opts.threads, &rmse, NULL);
    if (status == MR_OK && mask_path != NULL) {
        mr_img_read_options ro = {0};
        ro.encoding = MR_IMG_DATA; // coverage fractions, not colours
        ro.channels = 1;
        status = mr_img_read(mask_path, &ro, &mask);
        mr_ssim_options object = opts;
        object.mask = mask;
        if (status == MR_OK) status = mr_ssim(images[0], images[1], &object, &object_ssim, NULL);
        if (status == MR_OK)
            status = mr_rmse_masked(images[0], images[1], mask, opts.threads, &object_rmse, &object_mean);
    }
    if (status == MR_OK && map_path != NULL) {
        status = mr_ssim_map_visualise(map, 0.0, &picture);
        if (status == MR_OK) status = mr_img_write(map_path, picture, NULL);
    }
    if (status == MR_OK) {
        if (json && mask == NULL)
            printf("{\"ssim\": %.17g, \"rmse\": %.17g}\n", ssim, rmse);
        else if (json)
            printf("{\"ssim\": %.17g, \"rmse\": %.17g, \"object_ssim\": %.17g, \"object_rmse\": %.17g, "
                   "\"object_relative_rmse\": %.17g}\n", ssim, rmse, object_ssim, object_rmse,
                   object_mean > 0.0 ? object_rmse / object_mean : object_rmse);
        else
            printf("%.6f\n", mask != NULL ? object_ssim : ssim);
    }
    mr_image_free(images[0]);
    mr_image_free(images[1]);
    mr_image_free(map);
    mr_image_free(picture);
    mr_image_free(mask);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail("ssim", status);
}
