/*
 * view.h - what a visual station shows: a terminal displacement map of the dome
 * seen from above, and SVG snapshots of the deformed surface.
 */
#ifndef PALP_CLI_VIEW_H
#define PALP_CLI_VIEW_H

#include <stdio.h>

#include "palp_types.h"

typedef struct palp_cli_view {
  const palp_Phantom *phantom; /* rest mesh; borrowed */
  int w, h;                    /* character cells */
  int *cell_vertex;            /* [w*h] nearest dome vertex seen from above, -1 outside */
  double scale;                /* displacement at full colour [m]; 0 = automatic */
} palp_cli_view;

/* Checks a catalogue entry from the network before anything indexes with it:
 * vertex and triangle counts within bounds, every triangle index a vertex, the
 * dome triangle count and top vertex in range, radius and rest positions finite.
 * Returns 0, or PALP_EINVAL with the reason in err. */
int palp_cli_phantom_check(const palp_Phantom *ph, char *err, size_t errlen);
/* A deformation frame fits a checked phantom: one finite position per vertex. */
int palp_cli_deformation_check(const palp_Phantom *ph, const palp_Deformation *d);

int palp_cli_view_init(palp_cli_view *v, const palp_Phantom *ph, int w, int h, double scale);
void palp_cli_view_free(palp_cli_view *v);

/* Largest vertex displacement from rest [m] and the vertex it is at. */
double palp_cli_max_displacement(const palp_Phantom *ph, const palp_Deformation *d, int *vertex);

/* Draws the map (colour: ANSI 256-colour background cells; else characters). */
void palp_cli_view_render(const palp_cli_view *v, const palp_Deformation *d, FILE *out, int color);

/* Top view of the deformed dome, triangles coloured by displacement, drawn from
 * the lowest up. Returns 0 or a negative PALP_E* code. */
int palp_cli_view_svg(const palp_Phantom *ph, const palp_Deformation *d, const char *title, const char *path);

/* Makes s safe to print on a terminal, in place: control characters other than newline and tab (an
 * escape sequence, a carriage return that rewrites the line, a bell) and DEL become '?'. UTF-8 text
 * is left as it is. */
void palp_cli_terminal_safe(char *s);

#endif
