/* SPDX-License-Identifier: Apache-2.0 */
/* tmp-hold PATH: open PATH for atomic output (lie_atomic_open), write a
 * little, print the temporary's name and wait for a signal, as a tool does
 * in the middle of writing a large output.  For tests/tools/t0550: SIGINT
 * and SIGTERM must remove the temporary and still end the process by the
 * signal.  SIGINT is reset to its default first: a background job of a
 * non-interactive shell starts with it ignored, a tool in the foreground
 * does not. */
#include "common/cli.h"
#include "lie.h"

#include <signal.h>
#include <unistd.h>

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: tmp-hold PATH\n");
        return 2;
    }
    signal(SIGINT, SIG_DFL);
    signal(SIGHUP, SIG_DFL); /* ignored under nohup, which `nohup make test` passes on */
    lie_atomic_file af;
    lie_error err;
    if (lie_atomic_open(&af, argv[1], &err) != LIE_OK)
        return lie_report_error("tmp-hold", &err, 1);
    fputs("partial output\n", af.fp);
    fflush(af.fp);
    printf("%s\n", af.in_place ? "(in place)" : af.tmp);
    fflush(stdout);
    for (;;)
        pause();
}
