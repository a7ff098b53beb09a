/*
 * eval_report.c - Tables V and VI beside the paper's: terminal, CSV, JSON and
 * Markdown. Values are in the paper's units (cm for displacement, N for force).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "eval.h"

const char *palp_eval_roman(int d) {
  static const char *const r[] = {"?", "I", "II", "III", "IV"};
  return (d >= 1 && d <= 4) ? r[d] : r[0];
}

static const char *const table_name[2] = {"V", "VI"};
static const char *const quantity[2] = {"displacement", "force"};
static const char *const unit[2] = {"cm", "N"};

static const palp_eval_row *row_of(const palp_eval_dist *d, int t) {
  return t == 0 ? &d->disp : (d->has_force ? &d->force : NULL);
}

/* Why a row fails the paper's criteria, for the reader. */
static void verdict_text(const palp_eval_row *w, char *buf, size_t len) {
  if (w->meets) {
    snprintf(buf, len, "meets");
    return;
  }
  const int p_bad = !(w->anova.p > PALP_STATS_PAPER_ALPHA), a_bad = !(w->ba.agreement > PALP_STATS_PAPER_AGREEMENT);
  snprintf(buf, len, "fails (%s%s%s)", p_bad ? "p <= 0.05" : "", p_bad && a_bad ? ", " : "",
           a_bad ? "agreement <= 95%" : "");
}


/* NULL when not computed (fewer than 3 frames: no autocorrelation). */
static const palp_eval_sound *sound_of(const palp_eval_dist *d, int t) {
  const palp_eval_sound *w = t == 0 ? &d->disp_sound : (d->has_force ? &d->force_sound : NULL);
  return w && w->frames > 0 ? w : NULL;
}

/* The verdict of the second table, for the reader. */
static void sound_verdict(const palp_eval_sound *w, char *buf, size_t len) {
  if (w->equivalent) snprintf(buf, len, "equivalent");
  else if (!w->tost_valid)
    snprintf(buf, len, "not testable in one run (n_eff %.2g < 2; %s)", w->n_eff,
             w->boot_reliable ? "MBB usable" : "MBB unusable: block ~ record");
  else if (!w->tost.equivalent) snprintf(buf, len, "not shown (90%% CI leaves -+margin)");
  else if (!w->boot_reliable) snprintf(buf, len, "not shown (MBB unusable: %zu blocks)", w->boot.blocks);
  else snprintf(buf, len, "not shown (bootstrap CI leaves -+margin)");
}

/* The caveat written next to the paper's literal tables. */
static void paper_caveat(FILE *out, const palp_eval_report *r, int t, const char *prefix) {
  double rmin = 1, rmax = -1;
  size_t n = 0;
  for (int i = 0; i < r->dist_count; ++i) {
    const palp_eval_sound *w = sound_of(&r->dist[i], t);
    const palp_eval_row *row = row_of(&r->dist[i], t);
    if (!w || !row) continue;
    rmin = fmin(rmin, w->r1), rmax = fmax(rmax, w->r1);
    if (row->n > n) n = row->n; /* "up to": the largest row's, not the last one's */
  }
  if (rmax < rmin) return;
  /* worded from the values: the claim that p measures the sample size holds for a strongly
   * positively autocorrelated difference only (displacement, r1 ~0.99), not for force, whose
   * r1 is near -0.24 (it was printed for both until session 82) */
  if (rmin >= PALP_EVAL_CAVEAT_R1)
    fprintf(out,
            "%scaveat: the ANOVA pools up to %zu %s pairs of one deterministic run per distribution as if "
            "independent; the per-frame mean difference has a lag-1 autocorrelation from %.3f to %.3f, so its p "
            "measures the sample size, not agreement. See the second table.\n",
            prefix, n, t == 0 ? "vertex-frame" : "contact-vertex-frame", rmin, rmax);
  else
    fprintf(out,
            "%scaveat: the ANOVA pools up to %zu %s pairs of one deterministic run per distribution as if "
            "independent (repeated measures of one run); the per-frame mean difference has a lag-1 autocorrelation "
            "from %.3f to %.3f%s. See the second table.\n",
            prefix, n, t == 0 ? "vertex-frame" : "contact-vertex-frame", rmin, rmax,
            rmax >= PALP_EVAL_CAVEAT_R1 ? ", high in some distributions, where its p measures the sample size" : "");
}

static void print_sound(FILE *out, const palp_eval_report *r) {
  fprintf(out, "Second table: sound statistics (unit of analysis: the run; vertex-frames are repeated measures)\n");
  fprintf(out, "  TOST on the bias at alpha 0.05 per side; SE from the AR(1) effective number of frames n_eff and a\n"
               "  moving-block bootstrap of the per-frame mean difference (%d resamples, seeded); margins: displacement\n"
               "  max(5%%, min(1 mm, 15%%)) of the FEM peak, force 15%% of the FEM peak\n",
          PALP_EVAL_BOOT_RESAMPLES);
  for (int t = 0; t < 2; ++t) {
    fprintf(out, "%s [%s]\n", quantity[t], unit[t]);
    fprintf(out, "%-10s %10s %7s %6s %10s %5s %10s %23s %8s %8s  %s\n", "", "bias", "r1", "n_eff", "SE(n_eff)", "b",
            "SE(MBB)", "90% CI (MBB)", "margin", "TOST p", "verdict");
    for (int i = 0; i < r->dist_count; ++i) {
      const palp_eval_dist *d = &r->dist[i];
      const palp_eval_sound *w = sound_of(d, t);
      char name[16], v[96], p[32];
      snprintf(name, sizeof name, "Distr. %s", palp_eval_roman(d->distribution));
      if (!w) continue;
      sound_verdict(w, v, sizeof v);
      if (w->tost_valid) snprintf(p, sizeof p, "%.3g", w->tost.p);
      else snprintf(p, sizeof p, "-");
      fprintf(out, "%-10s %10.4g %7.4f %6.2f %10.3g %5zu %10.3g [%10.4g, %10.4g] %8.4g %8s  %s\n", name, w->bias, w->r1,
              w->n_eff, w->frame_sd / sqrt(w->n_eff), w->boot.block, w->boot.se, w->boot.ci_lower, w->boot.ci_upper,
              w->margin, p, v);
    }
    if (r->pooled[t]) {
      const palp_eval_sound_pool *q = &r->pool[t];
      fprintf(out,
              "%-10s %d runs: bias %.4g, repeated-measures LoA [%.4g, %.4g] (SD %.4g: within runs %.4g, between "
              "runs %.4g);\n%-10s TOST over run biases: 90%% CI [%.4g, %.4g], margin -+%.4g, p %.3g (%g df): %s\n",
              "pooled", q->runs, q->ba.bias, q->ba.loa_lower, q->ba.loa_upper, q->ba.sd_total, sqrt(q->ba.var_within),
              sqrt(q->ba.var_between), "", q->tost.ci_lower, q->tost.ci_upper, q->margin, q->tost.p, q->tost.df,
              q->tost.equivalent ? "equivalent" : "not shown");
    }
    fprintf(out, "\n");
  }
}

void palp_eval_report_print(FILE *out, const palp_eval_report *r) {
  fprintf(out, "scene %s (%s): %d frames of %.4g s, %d vertices; parameters %s\n", r->scene_name, r->scene,
           r->frames, r->frame_period, r->vertex_count, r->parameters);
  fprintf(out, "reference: FEM level %d (%d elements, %d nodes), material profile %s, %s load map\n\n", r->ref_level,
          r->ref_elements, r->ref_nodes, r->ref_material, r->ref_load_map);
  for (int t = 0; t < 2; ++t) {
    fprintf(out, "Table %s: %s, real-time model vs FEM (paper | measured)\n", table_name[t], quantity[t]);
    fprintf(out, "%-10s %8s %17s %15s %15s %17s %15s  %s\n", "", "pairs", "RMSE [", "F", "p", "SD [", "Agree [%]",
            "verdict");
    fprintf(out, "%-10s %8s %17s\n", "", "", t == 0 ? "cm]" : "N]");
    for (int i = 0; i < r->dist_count; ++i) {
      const palp_eval_dist *d = &r->dist[i];
      const palp_eval_paper_row *pp = &palp_eval_paper[t][d->distribution - 1];
      const palp_eval_row *w = row_of(d, t);
      char name[16];
      snprintf(name, sizeof name, "Distr. %s", palp_eval_roman(d->distribution));
      if (!w) {
        fprintf(out, "%-10s %8s   (no force feedback recorded)\n", name, "-");
        continue;
      }
      char v[64];
      verdict_text(w, v, sizeof v);
      fprintf(out, "%-10s %8zu %6.2f | %-8.4f %5.2f | %-7.3g %5.2f | %-7.3g %6.2f | %-8.4f %5.1f | %-6.1f  %s\n", name,
              w->n, pp->rmse, w->rmse, pp->f, w->anova.f, pp->p, w->anova.p, pp->sd, w->ba.sd, pp->agree_percent,
              100.0 * w->ba.agreement, v);
    }
    paper_caveat(out, r, t, "");
    fprintf(out, "\n");
  }
  fprintf(out, "criteria (paper, Sec. II-D): one-way ANOVA p > 0.05 and more than 95%% of the differences within "
               "bias +- 2 SD\n\n");
  /* An RMSE means little without the size of what it measures: a stiff profile's
   * whole displacement can be smaller than a fixed margin (docs/materials.md). */
  fprintf(out, "displacement against its scale (issue 12: RMSE at most 5%% of the FEM peak, or 1 mm; the model's peak "
               "within 10%%)\n");
  for (int i = 0; i < r->dist_count; ++i) {
    const palp_eval_row *w = &r->dist[i].disp;
    if (!(w->ref_peak > 0.0)) continue;
    fprintf(out, "  Distr. %-4s FEM peak %.4g cm, model peak %.4g cm (%+.1f%%), RMSE %.4g cm = %.1f%% of the FEM peak\n",
            palp_eval_roman(r->dist[i].distribution), w->ref_peak, w->rt_peak, 100.0 * (w->rt_peak / w->ref_peak - 1.0),
            w->rmse, 100.0 * w->rmse / w->ref_peak);
  }
  fprintf(out, "\n");
  print_sound(out, r);
}

static int write_csv(const char *path, const palp_eval_report *r) {
  FILE *f = fopen(path, "w");
  if (!f) return PALP_EIO;
  fprintf(f, "table,quantity,unit,distribution,pairs,rmse,bias,sd,loa_lower,loa_upper,agreement_percent,"
             "anova_f,anova_p,df_between,df_within,ss_between,ss_within,mean_rt,mean_ref,max_abs_diff,meets,"
             "paper_rmse,paper_f,paper_p,paper_sd,paper_agreement_percent\n");
  for (int t = 0; t < 2; ++t)
    for (int i = 0; i < r->dist_count; ++i) {
      const palp_eval_dist *d = &r->dist[i];
      const palp_eval_row *w = row_of(d, t);
      if (!w) continue;
      const palp_eval_paper_row *pp = &palp_eval_paper[t][d->distribution - 1];
      fprintf(f, "%s,%s,%s,%s,%zu,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%d,%ld,%.17g,%.17g,%.17g,%.17g,"
                 "%.17g,%d,%g,%g,%g,%g,%g\n",
              table_name[t], quantity[t], unit[t], palp_eval_roman(d->distribution), w->n, w->rmse, w->ba.bias,
              w->ba.sd, w->ba.loa_lower, w->ba.loa_upper, 100.0 * w->ba.agreement, w->anova.f, w->anova.p,
              w->anova.df_between, w->anova.df_within, w->anova.ss_between, w->anova.ss_within, w->ba.mean_a,
              w->ba.mean_b, w->max_abs_diff, w->meets, pp->rmse, pp->f, pp->p, pp->sd, pp->agree_percent);
    }
  int bad = ferror(f);
  bad |= fclose(f) != 0;
  return bad ? PALP_EIO : PALP_OK;
}

static cJSON *row_json(const palp_eval_row *w, const palp_eval_paper_row *pp) {
  cJSON *o = cJSON_CreateObject();
  cJSON_AddNumberToObject(o, "pairs", (double)w->n);
  cJSON_AddNumberToObject(o, "rmse", w->rmse);
  cJSON_AddNumberToObject(o, "bias", w->ba.bias);
  cJSON_AddNumberToObject(o, "sd", w->ba.sd);
  cJSON_AddNumberToObject(o, "loa_lower", w->ba.loa_lower);
  cJSON_AddNumberToObject(o, "loa_upper", w->ba.loa_upper);
  cJSON_AddNumberToObject(o, "within_band", (double)w->ba.within_band);
  cJSON_AddNumberToObject(o, "agreement_percent", 100.0 * w->ba.agreement);
  cJSON_AddNumberToObject(o, "mean_rt", w->ba.mean_a);
  cJSON_AddNumberToObject(o, "mean_ref", w->ba.mean_b);
  cJSON_AddNumberToObject(o, "max_abs_diff", w->max_abs_diff);
  cJSON_AddNumberToObject(o, "ref_peak", w->ref_peak);
  cJSON_AddNumberToObject(o, "rt_peak", w->rt_peak);
  cJSON *a = cJSON_AddObjectToObject(o, "anova");
  if (isfinite(w->anova.f)) cJSON_AddNumberToObject(a, "f", w->anova.f);
  else cJSON_AddNullToObject(a, "f");
  cJSON_AddNumberToObject(a, "p", w->anova.p);
  cJSON_AddNumberToObject(a, "df_between", w->anova.df_between);
  cJSON_AddNumberToObject(a, "df_within", (double)w->anova.df_within);
  cJSON_AddNumberToObject(a, "ss_between", w->anova.ss_between);
  cJSON_AddNumberToObject(a, "ss_within", w->anova.ss_within);
  cJSON_AddBoolToObject(o, "meets_paper_criteria", w->meets);
  cJSON *p = cJSON_AddObjectToObject(o, "paper");
  cJSON_AddNumberToObject(p, "rmse", pp->rmse);
  cJSON_AddNumberToObject(p, "f", pp->f);
  cJSON_AddNumberToObject(p, "p", pp->p);
  cJSON_AddNumberToObject(p, "sd", pp->sd);
  cJSON_AddNumberToObject(p, "agreement_percent", pp->agree_percent);
  return o;
}

static cJSON *sound_json(const palp_eval_sound *w) {
  cJSON *o = cJSON_CreateObject();
  cJSON_AddNumberToObject(o, "frames", w->frames);
  cJSON_AddNumberToObject(o, "bias", w->bias);
  cJSON_AddNumberToObject(o, "frame_sd", w->frame_sd);
  cJSON_AddNumberToObject(o, "r1", w->r1);
  cJSON_AddNumberToObject(o, "n_eff", w->n_eff);
  cJSON_AddNumberToObject(o, "margin", w->margin);
  cJSON_AddBoolToObject(o, "tost_valid", w->tost_valid);
  if (w->tost_valid) {
    cJSON_AddNumberToObject(o, "tost_se", w->tost.se);
    cJSON_AddNumberToObject(o, "tost_df", w->tost.df);
    cJSON_AddNumberToObject(o, "tost_p", w->tost.p);
    cJSON_AddNumberToObject(o, "tost_ci_lower", w->tost.ci_lower);
    cJSON_AddNumberToObject(o, "tost_ci_upper", w->tost.ci_upper);
  }
  cJSON_AddNumberToObject(o, "boot_block", (double)w->boot.block);
  cJSON_AddNumberToObject(o, "boot_resamples", (double)w->boot.resamples);
  cJSON_AddNumberToObject(o, "boot_se", w->boot.se);
  cJSON_AddNumberToObject(o, "boot_ci_lower", w->boot.ci_lower);
  cJSON_AddNumberToObject(o, "boot_ci_upper", w->boot.ci_upper);
  cJSON_AddNumberToObject(o, "boot_blocks_per_resample", (double)w->boot.blocks);
  cJSON_AddBoolToObject(o, "boot_reliable", w->boot_reliable);
  cJSON_AddBoolToObject(o, "boot_equivalent", w->boot_equivalent);
  cJSON_AddBoolToObject(o, "equivalent", w->equivalent);
  return o;
}

static int write_json(const char *path, const palp_eval_report *r) {
  cJSON *root = cJSON_CreateObject();
  cJSON_AddStringToObject(root, "scene", r->scene);
  cJSON_AddStringToObject(root, "scene_name", r->scene_name);
  cJSON_AddStringToObject(root, "parameters", r->parameters);
  cJSON_AddNumberToObject(root, "frames", r->frames);
  cJSON_AddNumberToObject(root, "frame_period_s", r->frame_period);
  cJSON_AddNumberToObject(root, "vertex_count", r->vertex_count);
  cJSON *ref = cJSON_AddObjectToObject(root, "reference");
  cJSON_AddStringToObject(ref, "model", "FEM (src/fem)");
  cJSON_AddNumberToObject(ref, "level", r->ref_level);
  cJSON_AddNumberToObject(ref, "elements", r->ref_elements);
  cJSON_AddNumberToObject(ref, "nodes", r->ref_nodes);
  cJSON_AddStringToObject(ref, "material", r->ref_material);
  cJSON_AddStringToObject(ref, "load_map", r->ref_load_map);
  cJSON *crit = cJSON_AddObjectToObject(root, "criteria");
  cJSON_AddNumberToObject(crit, "p_above", PALP_STATS_PAPER_ALPHA);
  cJSON_AddNumberToObject(crit, "agreement_above", PALP_STATS_PAPER_AGREEMENT);
  cJSON_AddNumberToObject(crit, "band_sd", PALP_STATS_PAPER_BAND_SD);
  cJSON *tables = cJSON_AddArrayToObject(root, "tables");
  for (int t = 0; t < 2; ++t) {
    cJSON *tab = cJSON_CreateObject();
    cJSON_AddStringToObject(tab, "table", table_name[t]);
    cJSON_AddStringToObject(tab, "quantity", quantity[t]);
    cJSON_AddStringToObject(tab, "unit", unit[t]);
    cJSON *rows = cJSON_AddArrayToObject(tab, "rows");
    for (int i = 0; i < r->dist_count; ++i) {
      const palp_eval_dist *d = &r->dist[i];
      const palp_eval_row *w = row_of(d, t);
      if (!w) continue;
      cJSON *o = row_json(w, &palp_eval_paper[t][d->distribution - 1]);
      cJSON_AddStringToObject(o, "distribution", palp_eval_roman(d->distribution));
      cJSON_AddNumberToObject(o, "vertices_per_frame", t == 0 ? d->disp_vertices : d->force_vertices);
      cJSON_AddNumberToObject(o, "rt_seconds", d->rt_seconds);
      cJSON_AddNumberToObject(o, "ref_seconds", d->ref_seconds);
      cJSON_AddBoolToObject(o, "ref_from_cache", d->ref_from_cache);
      if (sound_of(d, t)) cJSON_AddItemToObject(o, "sound", sound_json(sound_of(d, t)));
      cJSON_AddItemToArray(rows, o);
    }
    if (r->pooled[t]) {
      const palp_eval_sound_pool *q = &r->pool[t];
      cJSON *po = cJSON_AddObjectToObject(tab, "pooled");
      cJSON_AddNumberToObject(po, "runs", q->runs);
      cJSON_AddNumberToObject(po, "bias", q->ba.bias);
      cJSON_AddNumberToObject(po, "rm_loa_lower", q->ba.loa_lower);
      cJSON_AddNumberToObject(po, "rm_loa_upper", q->ba.loa_upper);
      cJSON_AddNumberToObject(po, "rm_sd_total", q->ba.sd_total);
      cJSON_AddNumberToObject(po, "rm_sd_within", sqrt(q->ba.var_within));
      cJSON_AddNumberToObject(po, "rm_sd_between", sqrt(q->ba.var_between));
      cJSON_AddNumberToObject(po, "margin", q->margin);
      cJSON_AddNumberToObject(po, "tost_mean_of_run_biases", q->tost.estimate);
      cJSON_AddNumberToObject(po, "tost_se", q->tost.se);
      cJSON_AddNumberToObject(po, "tost_df", q->tost.df);
      cJSON_AddNumberToObject(po, "tost_p", q->tost.p);
      cJSON_AddNumberToObject(po, "tost_ci_lower", q->tost.ci_lower);
      cJSON_AddNumberToObject(po, "tost_ci_upper", q->tost.ci_upper);
      cJSON_AddBoolToObject(po, "equivalent", q->tost.equivalent);
    }
    cJSON_AddItemToArray(tables, tab);
  }
  char *txt = cJSON_Print(root);
  cJSON_Delete(root);
  if (!txt) return PALP_ENOMEM;
  FILE *f = fopen(path, "w");
  if (!f) {
    free(txt);
    return PALP_EIO;
  }
  fprintf(f, "%s\n", txt);
  free(txt);
  int bad = ferror(f);
  bad |= fclose(f) != 0;
  return bad ? PALP_EIO : PALP_OK;
}

static int write_md(const char *path, const palp_eval_report *r) {
  FILE *f = fopen(path, "w");
  if (!f) return PALP_EIO;
  fprintf(f, "Scene `%s` (%d frames of %g s, %d vertices), parameters `%s`; reference: FEM level %d (%d elements), "
             "material profile `%s`, %s load map. Each cell: paper / measured.\n\n",
          r->scene_name, r->frames, r->frame_period, r->vertex_count, r->parameters, r->ref_level, r->ref_elements,
          r->ref_material, r->ref_load_map);
  for (int t = 0; t < 2; ++t) {
    fprintf(f, "**Table %s: %s**\n\n", table_name[t], quantity[t]);
    fprintf(f, "| | pairs | RMSE [%s] | F | p | SD [%s] | Agree [%%] | verdict |\n", unit[t], unit[t]);
    fprintf(f, "|---|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < r->dist_count; ++i) {
      const palp_eval_dist *d = &r->dist[i];
      const palp_eval_row *w = row_of(d, t);
      if (!w) continue;
      const palp_eval_paper_row *pp = &palp_eval_paper[t][d->distribution - 1];
      char v[64];
      verdict_text(w, v, sizeof v);
      fprintf(f, "| Distr. %s | %zu | %.2f / %.4f | %.2f / %.3g | %.2f / %.3g | %.2f / %.4f | %.1f / %.1f | %s |\n",
              palp_eval_roman(d->distribution), w->n, pp->rmse, w->rmse, pp->f, w->anova.f, pp->p, w->anova.p, pp->sd,
              w->ba.sd, pp->agree_percent, 100.0 * w->ba.agreement, v);
    }
    fprintf(f, "\n");
    paper_caveat(f, r, t, "_");
    fprintf(f, "\n");
  }
  fprintf(f, "**Second table: sound statistics** (unit of analysis: the run; TOST at alpha 0.05 per side; margins: "
             "displacement max(5%%, min(1 mm, 15%%)) of the FEM peak, force 15%% of the FEM peak)\n\n");
  for (int t = 0; t < 2; ++t) {
    fprintf(f, "| %s [%s] | bias | r1 | n_eff | SE (n_eff) | block | SE (MBB) | 90%% CI (MBB) | margin | TOST p | verdict |\n",
            quantity[t], unit[t]);
    fprintf(f, "|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (int i = 0; i < r->dist_count; ++i) {
      const palp_eval_dist *d = &r->dist[i];
      const palp_eval_sound *w = sound_of(d, t);
      if (!w) continue;
      char v[96], p[32];
      sound_verdict(w, v, sizeof v);
      if (w->tost_valid) snprintf(p, sizeof p, "%.3g", w->tost.p);
      else snprintf(p, sizeof p, "-");
      fprintf(f, "| Distr. %s | %.4g | %.4f | %.2f | %.3g | %zu | %.3g | [%.4g, %.4g] | %.4g | %s | %s |\n",
              palp_eval_roman(d->distribution), w->bias, w->r1, w->n_eff, w->frame_sd / sqrt(w->n_eff), w->boot.block,
              w->boot.se, w->boot.ci_lower, w->boot.ci_upper, w->margin, p, v);
    }
    if (r->pooled[t]) {
      const palp_eval_sound_pool *q = &r->pool[t];
      fprintf(f, "\nPooled over %d runs: bias %.4g %s; repeated-measures limits of agreement [%.4g, %.4g] (SD %.4g: "
                 "within runs %.4g, between runs %.4g); TOST over the run biases: 90%% CI [%.4g, %.4g] against -+%.4g, "
                 "p %.3g (%g df): %s.\n",
              q->runs, q->ba.bias, unit[t], q->ba.loa_lower, q->ba.loa_upper, q->ba.sd_total, sqrt(q->ba.var_within),
              sqrt(q->ba.var_between), q->tost.ci_lower, q->tost.ci_upper, q->margin, q->tost.p, q->tost.df,
              q->tost.equivalent ? "equivalent" : "not shown");
    }
    fprintf(f, "\n");
  }
  int bad = ferror(f);
  bad |= fclose(f) != 0;
  return bad ? PALP_EIO : PALP_OK;
}

int palp_eval_report_write(const char *dir, const palp_eval_report *r, char *err, size_t errlen) {
  char path[1024];
  snprintf(path, sizeof path, "%s/tables.csv", dir);
  int rc = write_csv(path, r);
  if (!rc) {
    snprintf(path, sizeof path, "%s/tables.json", dir);
    rc = write_json(path, r);
  }
  if (!rc) {
    snprintf(path, sizeof path, "%s/tables.md", dir);
    rc = write_md(path, r);
  }
  if (rc) snprintf(err, errlen, "cannot write %s: %s", path, palp_strerror(rc));
  return rc;
}
