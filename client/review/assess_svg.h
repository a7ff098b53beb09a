/* The assessment drawn in SVG (assess_svg.c): coverage maps per pressure band, the finger's
 * path, lesions and findings, and a small score chart. */
#ifndef PALP_REVIEW_ASSESS_SVG_H
#define PALP_REVIEW_ASSESS_SVG_H
#include <stdio.h>

#include "assess_log.h"

/* Okabe-Ito colours (distinguishable with the common colour-vision deficiencies). */
extern const char *const review_band_colour[3];
#define REVIEW_UNCOVERED_COLOUR "#e6e6e6"

/* The dome seen from above (12 o'clock = +y), its triangles filled in the band's colour where
 * palpated in that band (2 of 3 vertices), grey elsewhere. size_px: width and height. */
void review_svg_coverage(FILE *f, const review_assessment *a, int band, int size_px, const char *id);
/* The finger's path (contact points while touching), the revealed lesions (dashed circles of
 * their diameter) and the findings (found / false / withdrawn / duplicate, by shape and label). */
void review_svg_path(FILE *f, const review_assessment *a, int size_px, const char *id);
/* The finding's class name: "found", "false", "withdrawn" or "duplicate". */
const char *review_finding_class(int match);
/* Score per session, 0..100, as a small line chart. */
void review_svg_scores(FILE *f, const double *score, int n, int w, int h, const char *id);
#endif
