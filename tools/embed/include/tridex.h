/* tridex.h — tridex's C API: a milling session (a stock, a tool table, a program fed in pieces)
 * and questions about the stock as it stands. docs/embedding.md is its manual.
 *
 * Opaque handles, status codes, no exceptions across it: every call returns TRIDEX_OK or an
 * error status, and tridex_last_error() then says what went wrong (file:line where the program
 * is at fault). A session is used by one thread at a time; sessions are independent. */
#ifndef TRIDEX_H
#define TRIDEX_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum tridex_status {
  TRIDEX_OK = 0,
  TRIDEX_ERROR = 1,     /* an internal failure (out of memory, a bug): the message says which */
  TRIDEX_BAD_INPUT = 2, /* bad G-code, a tool missing from the table, a bad stock or option */
  TRIDEX_BAD_CALL = 3   /* a null handle or pointer */
} tridex_status;

typedef struct tridex_session tridex_session;

typedef struct tridex_session_options {
  double stock[6]; /* xmin, ymin, zmin, xmax, ymax, zmax (mm, work frame) */
  const char*
      tools; /* tool table file (CAMotics JSON, Fusion library, LinuxCNC .tbl); NULL: none */
  const char* machine; /* as --machine: a bundled machine's name or a machine file; NULL: default */
  double cell;         /* dexel spacing (mm), as --dexel-cell; 0: the default resolution */
  unsigned threads; /* every call's threads, started once per session; 0: every hardware thread */
  const char*
      stock_file; /* a closed STL as the stock (its bounds replace `stock`); NULL: the box */
} tridex_session_options;

/* The message of the calling thread's last failed call ("" when none); valid until its next call.
 */
const char* tridex_last_error(void);
/* The library's version, "major.minor.patch". */
const char* tridex_version(void);

tridex_status tridex_session_new(const tridex_session_options* options, tridex_session** out);
void tridex_session_free(tridex_session* session); /* NULL is allowed */

/* More program text; the interpreter's state is kept between calls, moves are cut as read. A
 * piece that fails leaves the session as it was. */
tridex_status tridex_session_feed(tridex_session* session, const char* text);
/* feed, and *removed = the mm^3 that piece removed (the solid is brought up to date before and
 * after it: two questions' cost). */
tridex_status tridex_session_feed_measured(tridex_session* session, const char* text,
                                           double* removed);
/* One straight move given directly, not as G-code: tool tip from start to end (mm, work frame:
 * the part's coordinates, as the stock), cut by tool `tool` of the table with its spindle along
 * axis (tip towards holder, any length); rapid != 0 marks a rapid (cut all the same, as simulate
 * does). The interpreter's state is untouched. */
tridex_status tridex_session_add_move(tridex_session* session, const double start[3],
                                      const double end[3], int tool, const double axis[3],
                                      int rapid);
/* mm^3 removed so far (the stock less the solid's surface volume). */
tridex_status tridex_session_removed_volume(tridex_session* session, double* out);
/* The depth (mm) the block would cut into the stock as it stands (0: none), without cutting. */
tridex_status tridex_session_would_cut(tridex_session* session, const char* block, double* out);
/* *out = 1 when the point (x, y, z) lies inside the stock as it stands, else 0. */
tridex_status tridex_session_inside(tridex_session* session, const double point[3], int* out);
/* The stock's extent along the line point + t*direction (t in mm along the unit direction): the
 * intervals [t_in, t_out] inside the solid, ascending, as spans[2k], spans[2k+1] for k < the
 * smaller of *count and capacity; *count is how many there are (call again with more room when
 * it exceeds capacity). The height at (x, y): the last t_out from (x, y, 0) along (0, 0, 1). */
tridex_status tridex_session_extent(tridex_session* session, const double point[3],
                                    const double direction[3], double* spans, int capacity,
                                    int* count);
/* The solid as binary STL (written atomically). */
tridex_status tridex_session_write_stl(tridex_session* session, const char* path);
/* Moves cut so far, and the session's warnings (index < count; the text stays valid until the
 * next feed). */
tridex_status tridex_session_moves(tridex_session* session, long long* out);
tridex_status tridex_session_warning_count(tridex_session* session, int* out);
const char* tridex_session_warning(tridex_session* session, int index);

#ifdef __cplusplus
}
#endif

#endif /* TRIDEX_H */
