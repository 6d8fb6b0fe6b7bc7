/* cli_output.c — text files the commands write themselves, atomically (contract in cli.h). */
#include <stdio.h>

#include "cli.h"

FILE *cli_output_open(const char *command, const char *path, mr_atomic_file *file) {
    FILE *f = NULL;
    mr_status status = mr_atomic_open_text(path, file, &f);
    if (status != MR_OK) cli_fail(command, status);
    return f;
}

int cli_output_close(const char *command, FILE *f, mr_atomic_file *file) {
    mr_status status = mr_atomic_close_text(f, file);
    if (status != MR_OK) cli_fail(command, status);
    return status == MR_OK;
}
