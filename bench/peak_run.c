/* SPDX-License-Identifier: AGPL-3.0-or-later */
/* peak_run: run one command and report its wall time, CPU time and peak
 * resident set, for bench/compression.py.
 *
 *   peak_run REPORT COMMAND [ARG...]
 *
 * Forks, execs COMMAND (its stdin, stdout and stderr are ours), reaps it
 * with wait4() and writes one line to REPORT:
 *   "<exit status> <wall s> <user s> <system s> <peak RSS KiB>"
 * (exit status: the code, or 128 + signal). Exits 0 when the report was
 * written, whatever COMMAND did.
 *
 * Why not os.wait4 in Python directly: Linux keeps a process' high-water
 * resident set across execve (exec_mmap records the old image's), so a
 * child forked from the Python harness reports at least the harness' own
 * size (about 14 MiB) as its peak. Forked from this small program, the
 * floor is this program's size (about 1 MiB), which the harness measures
 * with /bin/true and prints. */
#define _GNU_SOURCE
#include <stdio.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

int main(int argc, char** argv) {
  if (argc < 3) {
    fprintf(stderr, "usage: peak_run REPORT COMMAND [ARG...]\n");
    return 1;
  }
  struct timespec t0, t1;
  clock_gettime(CLOCK_MONOTONIC, &t0);
  pid_t pid = fork();
  if (pid < 0) {
    perror("peak_run: fork");
    return 2;
  }
  if (pid == 0) {
    execvp(argv[2], argv + 2);
    perror("peak_run: exec");
    _exit(127);
  }
  int status = 0;
  struct rusage ru;
  if (wait4(pid, &status, 0, &ru) < 0) {
    perror("peak_run: wait4");
    return 2;
  }
  clock_gettime(CLOCK_MONOTONIC, &t1);
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  FILE* f = fopen(argv[1], "w");
  if (!f) {
    perror("peak_run: report");
    return 2;
  }
  fprintf(f, "%d %.6f %.6f %.6f %ld\n", code, (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec),
          (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec,
          (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec, ru.ru_maxrss);
  return fclose(f) == 0 ? 0 : 2;
}
