/* The C API (tools/embed/include/tridex.h) from C: a session fed in two pieces, its questions,
 * the STL, and the statuses and messages of bad input and bad calls. argv[1]: a scratch folder. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "tridex.h"

static int failures = 0;
#define EXPECT(cond)                                                     \
  do {                                                                   \
    if (!(cond)) {                                                       \
      fprintf(stderr, "%s:%d: failed: %s\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                        \
    }                                                                    \
  } while (0)

int main(int argc, char** argv) {
  char tools[4096], stl[4096];
  if (argc < 2) return 2;
  snprintf(tools, sizeof tools, "%s/c_api_tools.json", argv[1]);
  snprintf(stl, sizeof stl, "%s/c_api.stl", argv[1]);
  FILE* table = fopen(tools, "w");
  if (!table) return 2;
  fputs(
      "{\"1\": {\"units\": \"mm\", \"shape\": \"cylindrical\", \"length\": 50, "
      "\"diameter\": 10}}\n",
      table);
  fclose(table);

  tridex_session_options options;
  memset(&options, 0, sizeof options);
  const double stock[6] = {0, 0, 0, 40, 40, 20};
  memcpy(options.stock, stock, sizeof stock);
  options.tools = tools;
  options.cell = 0.5;
  options.threads = 2;
  tridex_session* s = NULL;
  EXPECT(tridex_session_new(&options, &s) == TRIDEX_OK && s != NULL);
  if (!s) {
    fprintf(stderr, "%s\n", tridex_last_error());
    return 1;
  }
  EXPECT(tridex_session_feed(s, "G21 G90\nT1 M6\nS5000 M3\nG0 X20 Y20 Z30\nF500\n") == TRIDEX_OK);
  double removed = -1, depth = -1;
  EXPECT(tridex_session_removed_volume(s, &removed) == TRIDEX_OK && removed == 0);
  EXPECT(tridex_session_would_cut(s, "G1 Z15", &depth) == TRIDEX_OK && fabs(depth - 5) < 0.05);
  EXPECT(tridex_session_would_cut(s, "G1 Z25", &depth) == TRIDEX_OK && depth == 0);
  /* F500 from the first piece: a plunge 5 mm deep, a 10 mm hole. */
  EXPECT(tridex_session_feed(s, "G1 Z15\nG0 Z30\n") == TRIDEX_OK);
  EXPECT(tridex_session_removed_volume(s, &removed) == TRIDEX_OK &&
         fabs(removed - 3.14159265 * 25 * 5) < 0.03 * 3.14159265 * 25 * 5);
  int in = -1;
  const double below[3] = {20, 20, 14}, above[3] = {20, 20, 16};
  EXPECT(tridex_session_inside(s, below, &in) == TRIDEX_OK && in == 1);
  EXPECT(tridex_session_inside(s, above, &in) == TRIDEX_OK && in == 0);
  EXPECT(tridex_session_write_stl(s, stl) == TRIDEX_OK);
  FILE* written = fopen(stl, "rb");
  EXPECT(written != NULL);
  if (written) fclose(written);
  /* The height at (20, 20) and at (5, 5): the hole's bottom and the stock's top. */
  double spans[4] = {0, 0, 0, 0};
  int count = -1;
  const double hole[3] = {20, 20, 0}, corner[3] = {5, 5, 0}, up[3] = {0, 0, 1};
  EXPECT(tridex_session_extent(s, hole, up, spans, 2, &count) == TRIDEX_OK && count == 1 &&
         fabs(spans[0]) < 0.05 && fabs(spans[1] - 15) < 0.05);
  EXPECT(tridex_session_extent(s, corner, up, NULL, 0, &count) == TRIDEX_OK && count == 1);
  /* A move given directly: a slot 2 mm deep from x 20 to 30 at y 20 (tool 1, spindle +z), and
   * the removal of a piece. */
  const double from[3] = {20, 20, 18}, to[3] = {30, 20, 18};
  EXPECT(tridex_session_add_move(s, from, to, 1, up, 0) == TRIDEX_OK);
  double before = -1, piece = -1;
  EXPECT(tridex_session_removed_volume(s, &before) == TRIDEX_OK && before > removed + 150);
  EXPECT(tridex_session_feed_measured(s, "G0 X30 Y30\nG1 Z17\nG0 Z30\n", &piece) == TRIDEX_OK);
  EXPECT(tridex_session_removed_volume(s, &removed) == TRIDEX_OK && piece > 0 &&
         fabs(removed - before - piece) < 1e-6);
  EXPECT(tridex_session_add_move(s, from, to, 9, up, 0) == TRIDEX_BAD_INPUT);
  long long moves = 0;
  EXPECT(tridex_session_moves(s, &moves) == TRIDEX_OK && moves > 0);

  /* Bad input: status 2 and a message naming the line; the session is unchanged. */
  EXPECT(tridex_session_feed(s, "G1 X10\nG1 Q\n") == TRIDEX_BAD_INPUT);
  /* Line numbers run on across pieces: 5 + 2 + 3 lines before, the second line of this one. */
  EXPECT(strstr(tridex_last_error(), "<fed>:12:") != NULL);
  long long after = 0;
  EXPECT(tridex_session_moves(s, &after) == TRIDEX_OK && after == moves);
  EXPECT(tridex_session_feed(s, "T9 M6\nG1 X5 Z10\n") == TRIDEX_BAD_INPUT);
  EXPECT(strstr(tridex_last_error(), "tool 9") != NULL);
  /* Bad calls. */
  EXPECT(tridex_session_feed(NULL, "G0 X0") == TRIDEX_BAD_CALL);
  EXPECT(tridex_session_removed_volume(s, NULL) == TRIDEX_BAD_CALL);
  tridex_session_free(s);

  tridex_session* bad = NULL;
  options.stock[3] = -1; /* xmax below xmin */
  EXPECT(tridex_session_new(&options, &bad) == TRIDEX_BAD_INPUT && bad == NULL);
  EXPECT(strstr(tridex_last_error(), "stock") != NULL);
  options.stock[3] = 40;
  options.machine = "no-such-machine";
  EXPECT(tridex_session_new(&options, &bad) == TRIDEX_BAD_INPUT && bad == NULL);
  tridex_session_free(NULL);
  if (failures == 0) printf("c_api: all passed (tridex %s)\n", tridex_version());
  return failures == 0 ? 0 : 1;
}
