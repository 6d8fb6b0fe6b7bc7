/*
 * brdf_eval.c — a tiny driver for the cross-checks in tests/*.sh: evaluates one registered BRDF model at the
 * parameter vectors and direction pairs read from standard input and prints the diffuse and specular parts.
 * Built by the script that uses it against build/libmatremap.a (only the brdf module is linked in).
 *
 * Input, one case per line:   MODEL NAME=VALUE[,..] ... ; WI_X WI_Y WI_Z ; WO_X WO_Y WO_Z
 * (assignments as on the command line, applied to the model's defaults). Output, one line per case:
 *   D_R D_G D_B S_R S_G S_B   (%.17g), or "error: MESSAGE" for a line that does not parse.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdf/brdf.h"
#include "mr_status.h"

int main(void) {
    char line[4096];
    while (fgets(line, sizeof line, stdin)) {
        char *semi1 = strchr(line, ';'), *semi2 = semi1 ? strchr(semi1 + 1, ';') : NULL;
        if (!semi2) {
            printf("error: expected MODEL ASSIGNMENTS ; WI ; WO\n");
            continue;
        }
        *semi1 = *semi2 = '\0';
        char *save = NULL, *tok = strtok_r(line, " \t", &save);
        const mr_brdf_model *m = tok ? mr_brdf_find(tok) : NULL;
        if (!m) {
            printf("error: %s\n", mr_last_error());
            continue;
        }
        double v[MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(m, v);
        int ok = 1;
        while ((tok = strtok_r(NULL, " \t", &save)) != NULL)
            if (mr_brdf_parse_assignment(m, tok, v) != MR_OK) {
                printf("error: %s\n", mr_last_error());
                ok = 0;
                break;
            }
        if (!ok) continue;
        double wi[3], wo[3];
        if (sscanf(semi1 + 1, "%lf %lf %lf", &wi[0], &wi[1], &wi[2]) != 3 ||
            sscanf(semi2 + 1, "%lf %lf %lf", &wo[0], &wo[1], &wo[2]) != 3) {
            printf("error: bad directions\n");
            continue;
        }
        mr_brdf_state st;
        double d[3], s[3];
        m->prepare(m, v, st.bytes);
        m->eval(st.bytes, wi, wo, d, s);
        printf("%.17g %.17g %.17g %.17g %.17g %.17g\n", d[0], d[1], d[2], s[0], s[1], s[2]);
    }
    return 0;
}
