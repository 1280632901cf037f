/* A C program outside the project that uses the installed C API: a session with no tool table
 * (a program that only moves in the air needs none) fed one piece. */
#include <stdio.h>
#include <string.h>

#include <tridex.h>

int main(void) {
  tridex_session_options options;
  memset(&options, 0, sizeof options);
  const double stock[6] = {0, 0, 0, 10, 10, 5};
  memcpy(options.stock, stock, sizeof stock);
  options.cell = 1;
  tridex_session* s = NULL;
  double removed = -1;
  int in = 0;
  const double centre[3] = {5, 5, 2.5};
  if (tridex_session_new(&options, &s) != TRIDEX_OK ||
      tridex_session_feed(s, "G21 G90\nG0 X20 Y20\n") != TRIDEX_OK ||
      tridex_session_removed_volume(s, &removed) != TRIDEX_OK ||
      tridex_session_inside(s, centre, &in) != TRIDEX_OK) {
    fprintf(stderr, "tridex: %s\n", tridex_last_error());
    return 1;
  }
  printf("tridex %s: removed %g mm^3, centre inside: %d\n", tridex_version(), removed, in);
  tridex_session_free(s);
  return removed == 0 && in == 1 ? 0 : 1;
}
