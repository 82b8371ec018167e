/*
 * Render conetrace's built-in default scene through the C API and write an OpenEXR file.
 *
 *   render OUTPUT.exr [WIDTH HEIGHT]
 *
 * Build (see docs/c-api.md):
 *   cc examples/c/render.c $(pkg-config --cflags --libs conetrace) -o render
 * tests/c_api.rs compiles and runs this file and checks the EXR's channels.
 */
#include <stdio.h>
#include <stdlib.h>

#include "conetrace.h"

/* Print the failing call, its status and the library's message, then exit. */
static void check(CtStatus status, const char *what) {
    if (status != CT_OK) {
        fprintf(stderr, "%s failed: %s: %s\n", what, ct_status_name((int32_t)status),
                ct_last_error_message());
        exit(1);
    }
}

/* Progress callback: called on the thread that called ct_render, while the workers go on
   rendering; 0 = keep going. */
static int32_t on_progress(uint32_t finished_tiles, uint32_t total_tiles, void *user_data) {
    uint32_t *last = (uint32_t *)user_data;
    *last = finished_tiles;
    (void)total_tiles;
    return 0;
}

int main(int argc, char **argv) {
    if (argc != 2 && argc != 4) {
        fprintf(stderr, "usage: %s OUTPUT.exr [WIDTH HEIGHT]\n", argv[0]);
        return 2;
    }
    printf("conetrace %s (C ABI %u)\n", ct_version(), ct_abi_version());

    CtScene scene;
    check(ct_scene_default(&scene), "ct_scene_default");

    CtRenderOptions options;
    check(ct_render_options_init(&options, sizeof options), "ct_render_options_init");
    if (argc == 4) {
        options.width = (uint32_t)atoi(argv[2]);
        options.height = (uint32_t)atoi(argv[3]);
    }
    uint32_t finished = 0;
    options.progress = on_progress;
    options.progress_user_data = &finished;

    CtImage image;
    check(ct_render(scene, &options, &image), "ct_render");
    check(ct_scene_free(scene), "ct_scene_free");

    uint32_t width = 0, height = 0, channels = 0;
    check(ct_image_size(image, &width, &height), "ct_image_size");
    check(ct_image_channel_count(image, &channels), "ct_image_channel_count");
    printf("rendered %ux%u, %u tiles, channels:", width, height, finished);
    for (uint32_t c = 0; c < channels; ++c) {
        const char *name = NULL;
        check(ct_image_channel_name(image, c, &name), "ct_image_channel_name");
        printf(" %s", name);
    }
    printf("\n");

    /* Mean of the red plane, read through the pixel pointer. */
    uint32_t red = 0;
    const float *pixels = NULL;
    size_t count = 0;
    check(ct_image_find_channel(image, "R", &red), "ct_image_find_channel");
    check(ct_image_channel_pixels(image, red, &pixels, &count), "ct_image_channel_pixels");
    double sum = 0.0;
    for (size_t i = 0; i < count; ++i) sum += pixels[i];
    printf("mean R %.4f\n", count ? sum / (double)count : 0.0);

    check(ct_image_write_exr(image, argv[1]), "ct_image_write_exr");
    check(ct_image_free(image), "ct_image_free");
    printf("wrote %s\n", argv[1]);
    return 0;
}
