// bauv.hydro: the BAUV's run-time hydrodynamics as a MuJoCo engine plugin (passive forces).
//
// MuJoCo's ellipsoid fluid model gives drag, lift and the velocity terms of added mass, but not the
// acceleration term of added mass (engine_passive.c: "disabled due to dependency on qacc"), no
// crossflow drag across a streamlined hull, a Kutta lift whose slope near zero angle grows with the
// chord/thickness ratio, and no reaction to an accelerating current. One instance of this plugin
// per vehicle (instance "<prefix>hydro", the vehicle's elements "<prefix>...") adds, at every step:
//
//   * added mass M_A (6 x 6, hull origin and frame, numeric "<prefix>hydro_added_mass"): added to
//     the free joint's block of the mass matrix, T^T M_A T with T = diag(R^T, I), which is then
//     refactored (implicit in the acceleration, stable at any step), and M_A (w x nu_r +
//     R^T a_water) as a force (the rest of -M_A d(nu_r)/dt in the body frame); the hull's
//     potential coupling -C_B(nu_r) nu_r of its own added mass B ("<prefix>hydro_body_added_mass",
//     default M_A) with the Munk moment (Fossen 2021, eq. 6.43; Kirchhoff's equations, Lamb 1932
//     ch. 6): the lifting plates' potential couple is replaced by their circulation (Kutta
//     condition: their lift below). MuJoCo's own virtual masses of the vehicle's fluid geoms are
//     zeroed (their velocity terms alone are not physics);
//   * crossflow drag by strip theory, -1/2 rho C a |c| c per element ("<prefix>hydro_crossflow":
//     x y z a_y a_z C_y C_z in the hull frame), and the hull sections' roll damping
//     ("<prefix>hydro_roll_damping");
//   * the same for body segments that move on their own (the peduncle), in each segment body's
//     own frame and with its own velocity (translation and rotation, the tail's flapping
//     included): text "<prefix>hydro_segments" names the bodies, numeric
//     "<prefix>hydro_segment_crossflow" holds 8 numbers per strip (segment index, x y z in that
//     body's frame, a_y a_z C_y C_z) and "<prefix>hydro_segment_roll_damping" one K per segment
//     (torque -K p |p| about the body's x);
//   * the hull's slender-body lift with separation at x_s: -rho u A(x_s) c(x_s)
//     ("<prefix>hydro_slender_lift": x_y A_y x_z A_z f_y f_z) and the afterbody's share f of the
//     hull's Munk couple removed (lost to separation, Hopkins 1951);
//   * thin-plate lift 1/2 rho S C_La sin(a) cos(a) |u|^2 in each plate's chord-normal plane, at its
//     quarter chord (text "<prefix>hydro_foils": geom names; numeric "<prefix>hydro_foil_cla": C_La
//     per plate; chord along the geom's x, normal along its thinnest axis, S = pi a_chord a_span);
//   * thin-plate drag (numeric "<prefix>hydro_foil_drag": C_D0 k_i C_N per plate, zeros for a plate
//     whose drag is MuJoCo's): at the centre, the profile drag -1/2 rho S C_D0 |u_t| u_t of the
//     in-plane velocity u_t (skin friction on both faces with the section's form factor) and the
//     lift-induced drag 1/2 rho S k_i C_L^2 |u|^2 against the chord-normal velocity (C_L of the
//     lift above, k_i = 1/(pi e A)); over a grid of NSPAN x NCHORD panels of the plate's ellipse,
//     the normal (crossflow) force -1/2 rho C_N dA |u_n| u_n of each panel's normal velocity
//     (translation and rotation);
//   * the Froude-Krylov force rho V a_water on every displacing body (gravcomp x mass);
//   * MuJoCo's ellipsoid fluid model of every fluid geom of the vehicle (MuJoCo documentation,
//     "Fluid forces": Stokes, blunt and slender quadratic drag, angular drag, Kutta and Magnus
//     lift; not its virtual-mass velocity terms, which the added mass above replaces), in the
//     vehicle's own water, summed per body and applied once per body, when the model gives the
//     water as numeric "<prefix>hydro_water" (density kg/m^3, viscosity Pa s) with MuJoCo's own
//     fluid model off (option density and viscosity 0: the model file's default since issue 27;
//     the step then computes neither MuJoCo's fluid forces nor their velocity derivatives, which
//     were half of its cost, and these forces are explicit in the step);
//   * without "<prefix>hydro_water" (MuJoCo's fluid model on, the water is option density and
//     viscosity), for a vehicle whose water is not MuJoCo's (option wind: the first vehicle's),
//     the change of MuJoCo's translational drag (blunt, slender, Stokes) of its fluid geoms in its
//     own water.
//
// The water at the vehicle is the plugin's state (7 numbers: w0[3], a[3], t0): w(t) = w0 + a (t -
// t0), set by the simulator once per control tick (bauv_sim/hydro.py, set_water). The Python
// module bauv_sim/hydro.py holds the same equations as a reference implementation; the tests
// compare the two.

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <mujoco/mujoco.h>

#define NSTATE 7
#define NAME_LEN 1024
#define NSPAN 8    // span strips of a plate's normal-force panels
#define NCHORD 4   // chordwise panels per strip
#define NPANEL (NSPAN * NCHORD)

typedef struct {
  int free_body;     // body of the vehicle's free joint
  int dof;           // first dof of the free joint
  mjtNum MA[36];     // added mass of the vehicle, row-major, order (v, w): the mass matrix
  mjtNum MB[36];     // added mass of the hull alone: its potential coupling C_A(nu) nu
  int midx[21];      // positions of the free joint's lower-triangle block in d->M
  int mrow[21];
  int mcol[21];
  mjtNum last_blk[21];
  int have_last;
  int ncross;
  mjtNum* cross;     // 7 per element
  int has_slender;
  mjtNum slender[6];
  mjtNum roll_k;
  int nfoil;
  int* foil_geom;
  mjtNum* foil_k;    // 1/2 rho S C_La
  int* foil_normal;
  mjtNum* foil_drag; // per plate: 1/2 rho S C_D0, 1/2 rho S k_i C_La^2, 1/2 rho C_N
  mjtNum* panel;     // per plate NPANEL x (chord, span position in the geom frame (m), the
                     // panel's -1/2 rho C_N dA (kg/m))
  int ndrag;
  int* drag_geom;    // every fluid geom of the vehicle
  int nfk;
  int* fk_body;
  int nfluid;
  int* fluid_geom;
  int nkutta;
  int* kutta_geom;
  int nseg;
  int* seg_body;     // bodies whose own frames carry crossflow strips
  mjtNum* seg_roll;  // per segment: roll damping K (N m s^2)
  int nsegstrip;
  mjtNum* seg_strip; // 8 per strip: segment, x y z (its body frame), a_y a_z C_y C_z
  int own_fluid;     // 1: the plugin applies the ellipsoid model (numeric "<prefix>hydro_water")
  mjtNum rho;        // water density, kg/m^3
  mjtNum mu;         // water dynamic viscosity, Pa s
  int nbody;         // the model's bodies (sizes of the wrench accumulator)
  mjtNum* acc;       // per weld body: force (3, N, world) and moment about its xipos (3, N m)
  char* acc_on;      // per weld body: holds a wrench of this evaluation
  int* acc_list;     // the weld bodies holding one, in the order they were first touched
  int nacc;
} Hydro;

static void hydro_free(Hydro* h) {
  if (!h) return;
  free(h->cross);
  free(h->foil_geom);
  free(h->foil_k);
  free(h->foil_normal);
  free(h->foil_drag);
  free(h->panel);
  free(h->drag_geom);
  free(h->fk_body);
  free(h->fluid_geom);
  free(h->kutta_geom);
  free(h->seg_body);
  free(h->seg_roll);
  free(h->seg_strip);
  free(h->acc);
  free(h->acc_on);
  free(h->acc_list);
  free(h);
}

static int* dup_int(const int* a, int n) {
  if (n <= 0) return NULL;
  int* b = (int*)malloc(sizeof(int) * n);
  memcpy(b, a, sizeof(int) * n);
  return b;
}

static mjtNum* dup_num(const mjtNum* a, int n) {
  if (n <= 0) return NULL;
  mjtNum* b = (mjtNum*)malloc(sizeof(mjtNum) * n);
  memcpy(b, a, sizeof(mjtNum) * n);
  return b;
}

static Hydro* hydro_copy(const Hydro* s) {
  Hydro* h = (Hydro*)malloc(sizeof(Hydro));
  *h = *s;
  h->cross = dup_num(s->cross, 7 * s->ncross);
  h->foil_geom = dup_int(s->foil_geom, s->nfoil);
  h->foil_k = dup_num(s->foil_k, s->nfoil);
  h->foil_normal = dup_int(s->foil_normal, s->nfoil);
  h->foil_drag = dup_num(s->foil_drag, 3 * s->nfoil);
  h->panel = dup_num(s->panel, 3 * NPANEL * s->nfoil);
  h->drag_geom = dup_int(s->drag_geom, s->ndrag);
  h->fk_body = dup_int(s->fk_body, s->nfk);
  h->fluid_geom = dup_int(s->fluid_geom, s->nfluid);
  h->kutta_geom = dup_int(s->kutta_geom, s->nkutta);
  h->seg_body = dup_int(s->seg_body, s->nseg);
  h->seg_roll = dup_num(s->seg_roll, s->nseg);
  h->seg_strip = dup_num(s->seg_strip, 8 * s->nsegstrip);
  h->acc = (mjtNum*)calloc(6 * (s->nbody + 1), sizeof(mjtNum));
  h->acc_on = (char*)calloc(s->nbody + 1, 1);
  h->acc_list = (int*)calloc(s->nbody + 1, sizeof(int));
  h->nacc = 0;
  return h;
}

// numeric "<prefix><name>": its data and size, or NULL
static const mjtNum* numeric(const mjModel* m, const char* prefix, const char* name, int* size) {
  char full[NAME_LEN];  // prefix (< NAME_LEN / 2) and a short name
  snprintf(full, NAME_LEN, "%s%s", prefix, name);
  int id = mj_name2id(m, mjOBJ_NUMERIC, full);
  if (id < 0) return NULL;
  *size = m->numeric_size[id];
  return m->numeric_data + m->numeric_adr[id];
}

static int in_subtree(const mjModel* m, int body, int root) {
  while (body > 0) {
    if (body == root) return 1;
    body = m->body_parentid[body];
  }
  return root == 0;
}

static int fail(const char* instance, const char* what) {
  mju_warning("bauv.hydro instance '%s': %s", instance, what);
  return -1;
}

static void zero_model_terms(const mjModel* m, const Hydro* h) {
  // MuJoCo's virtual masses (velocity terms only) and the Kutta lift this plugin replaces; the
  // model is const to plugins, but these are per-geom parameters nothing else reads
  mjtNum* fluid = (mjtNum*)m->geom_fluid;
  for (int i = 0; i < h->nfluid; i++) {
    mjtNum* f = fluid + mjNFLUID * h->fluid_geom[i];
    for (int k = 6; k < 12; k++) f[k] = 0;
  }
  for (int i = 0; i < h->nkutta; i++) fluid[mjNFLUID * h->kutta_geom[i] + 4] = 0;
}

// the whitespace-separated names of a text element: its text copied into buf (cut to
// buf_size - 1 characters and terminated), and how many names it holds
static int text_names(const mjModel* m, int tid, char* buf, int buf_size) {
  int len = m->text_size[tid];
  if (len >= buf_size) len = buf_size - 1;
  memcpy(buf, m->text_data + m->text_adr[tid], len);
  buf[len] = '\0';
  const char* sep = " \t\n";
  int count = 0;
  for (const char* p = buf + strspn(buf, sep); *p; p += strspn(p, sep)) {
    count++;
    p += strcspn(p, sep);
  }
  return count;
}

// the segments' strips: text "<prefix>hydro_segments" (body names), numeric
// "<prefix>hydro_segment_crossflow" (8 per strip), "<prefix>hydro_segment_roll_damping" (1 per
// segment, optional); 0, or -1 with *what set
static int read_segments(const mjModel* m, const char* prefix, int fb, Hydro* h,
                         const char** what) {
  char full[NAME_LEN];
  snprintf(full, NAME_LEN, "%shydro_segments", prefix);
  int tid = mj_name2id(m, mjOBJ_TEXT, full);
  int size = 0;
  const mjtNum* sc = numeric(m, prefix, "hydro_segment_crossflow", &size);
  int strip_size = size;
  if (tid < 0) {
    if (sc) {
      *what = "'<prefix>hydro_segment_crossflow' needs the text '<prefix>hydro_segments'";
      return -1;
    }
    return 0;
  }
  char buf[4096];
  int count = text_names(m, tid, buf, (int)sizeof(buf));
  h->seg_body = (int*)malloc(sizeof(int) * (count + 1));
  h->seg_roll = (mjtNum*)calloc(count + 1, sizeof(mjtNum));
  char* save = NULL;
  for (char* tok = strtok_r(buf, " \t\n", &save); tok; tok = strtok_r(NULL, " \t\n", &save)) {
    snprintf(full, NAME_LEN, "%s%s", prefix, tok);
    int b = mj_name2id(m, mjOBJ_BODY, full);
    if (b < 0 || !in_subtree(m, b, fb)) {
      *what = "a body of '<prefix>hydro_segments' is not in the vehicle";
      return -1;
    }
    h->seg_body[h->nseg++] = b;
  }
  if (!sc || strip_size % 8) {
    *what = "'<prefix>hydro_segment_crossflow' must hold 8 numbers per strip";
    return -1;
  }
  h->nsegstrip = strip_size / 8;
  for (int k = 0; k < h->nsegstrip; k++) {
    mjtNum i = sc[8 * k];
    if (!(i >= 0 && i < count && i == floor(i))) {
      *what = "a strip of '<prefix>hydro_segment_crossflow' names no segment";
      return -1;
    }
  }
  h->seg_strip = dup_num(sc, strip_size);
  const mjtNum* rk = numeric(m, prefix, "hydro_segment_roll_damping", &size);
  if (rk) {
    if (size != count) {
      *what = "'<prefix>hydro_segment_roll_damping' must give one K per segment";
      return -1;
    }
    for (int i = 0; i < count; i++) h->seg_roll[i] = rk[i];
  }
  return 0;
}

static int hydro_init(const mjModel* m, mjData* d, int instance) {
  const char* iname = mj_id2name(m, mjOBJ_PLUGIN, instance);
  if (!iname) iname = "";
  char prefix[NAME_LEN / 2];
  size_t n = strlen(iname);
  const size_t ns = strlen("hydro");
  if (n < ns || n - ns >= NAME_LEN / 2 || strcmp(iname + n - ns, "hydro") != 0) {
    return fail(iname, "the instance must be named '<prefix>hydro'");
  }
  memcpy(prefix, iname, n - ns);
  prefix[n - ns] = '\0';

  Hydro* h = (Hydro*)calloc(1, sizeof(Hydro));
  char full[NAME_LEN];
  snprintf(full, NAME_LEN, "%shull", prefix);
  int hullb = mj_name2id(m, mjOBJ_BODY, full);
  if (hullb < 0) {
    hydro_free(h);
    return fail(iname, "no body '<prefix>hull'");
  }
  int fb = hullb;
  while (m->body_jntnum[fb] == 0 && m->body_parentid[fb] != 0) fb = m->body_parentid[fb];
  int j = m->body_jntadr[fb];
  if (j < 0 || m->jnt_type[j] != mjJNT_FREE) {
    hydro_free(h);
    return fail(iname, "the hull has no free joint");
  }
  h->free_body = fb;
  h->dof = m->jnt_dofadr[j];
  h->nbody = m->nbody;
  h->acc = (mjtNum*)calloc(6 * (m->nbody + 1), sizeof(mjtNum));
  h->acc_on = (char*)calloc(m->nbody + 1, 1);
  h->acc_list = (int*)calloc(m->nbody + 1, sizeof(int));

  int size = 0;
  const mjtNum* water = numeric(m, prefix, "hydro_water", &size);
  if (water) {
    if (size != 2 || !(water[0] > 0) || !(water[1] >= 0)) {
      hydro_free(h);
      return fail(iname, "numeric '<prefix>hydro_water' must hold density > 0 and viscosity >= 0");
    }
    if (m->opt.density != 0 || m->opt.viscosity != 0) {
      hydro_free(h);
      return fail(iname,
                  "numeric '<prefix>hydro_water' makes the plugin apply the ellipsoid fluid "
                  "model: option density and viscosity must be 0 (MuJoCo's would count twice)");
    }
    h->own_fluid = 1;
    h->rho = water[0];
    h->mu = water[1];
  } else {
    h->rho = m->opt.density;
    h->mu = m->opt.viscosity;
  }
  const mjtNum* ma = numeric(m, prefix, "hydro_added_mass", &size);
  if (!ma || size != 36) {
    hydro_free(h);
    return fail(iname, "numeric '<prefix>hydro_added_mass' (36 numbers) missing");
  }
  for (int k = 0; k < 36; k++) h->MA[k] = ma[k];
  const mjtNum* mb = numeric(m, prefix, "hydro_body_added_mass", &size);
  if (mb && size != 36) {
    hydro_free(h);
    return fail(iname, "numeric '<prefix>hydro_body_added_mass' must hold 36 numbers");
  }
  for (int k = 0; k < 36; k++) h->MB[k] = mb ? mb[k] : ma[k];

  for (int i = 0; i < 6; i++) {
    int r = h->dof + i;
    int adr = m->M_rowadr[r], nnz = m->M_rownnz[r];
    for (int c = 0; c <= i; c++) {
      int pos = -1;
      for (int k = 0; k < nnz; k++) {
        if (m->M_colind[adr + k] == h->dof + c) {
          pos = adr + k;
          break;
        }
      }
      if (pos < 0) {
        hydro_free(h);
        return fail(iname,
                    "the free joint's 6 x 6 block is not in the mass matrix's sparsity (MuJoCo "
                    "treats a lone body as 'simple', with a diagonal block): weld a child body "
                    "to the hull");
      }
      int e = i * (i + 1) / 2 + c;
      h->midx[e] = pos;
      h->mrow[e] = i;
      h->mcol[e] = c;
    }
  }

  const mjtNum* cr = numeric(m, prefix, "hydro_crossflow", &size);
  if (cr) {
    if (size % 7) {
      hydro_free(h);
      return fail(iname, "numeric '<prefix>hydro_crossflow' must hold 7 numbers per element");
    }
    h->ncross = size / 7;
    h->cross = dup_num(cr, size);
  }
  const mjtNum* sl = numeric(m, prefix, "hydro_slender_lift", &size);
  if (sl) {
    if (size != 6) {
      hydro_free(h);
      return fail(iname, "numeric '<prefix>hydro_slender_lift' must hold x_y A_y x_z A_z f_y f_z");
    }
    h->has_slender = 1;
    for (int k = 0; k < 6; k++) h->slender[k] = sl[k];
  }
  const mjtNum* rk = numeric(m, prefix, "hydro_roll_damping", &size);
  h->roll_k = (rk && size >= 1) ? rk[0] : 0;
  const char* what = "";
  if (read_segments(m, prefix, fb, h, &what) != 0) {
    hydro_free(h);
    return fail(iname, what);
  }

  // vehicle geoms and bodies
  h->fluid_geom = (int*)malloc(sizeof(int) * (m->ngeom + 1));
  h->drag_geom = (int*)malloc(sizeof(int) * (m->ngeom + 1));
  h->kutta_geom = (int*)malloc(sizeof(int) * (m->ngeom + 1));
  for (int g = 0; g < m->ngeom; g++) {
    if (!(m->geom_fluid[mjNFLUID * g] > 0)) continue;
    if (!in_subtree(m, m->geom_bodyid[g], fb)) continue;
    h->fluid_geom[h->nfluid++] = g;
    h->drag_geom[h->ndrag++] = g;  // every fluid geom: Stokes drag has no coefficient
    // the hull's own thick geoms: their lift is the slender-body lift
    int b = m->geom_bodyid[g];
    int on_hull = (b == fb) || (m->body_parentid[b] == fb && m->body_jntnum[b] == 0);
    const mjtNum* s = m->geom_size + 3 * g;
    mjtNum lo = fmin(s[0], fmin(s[1], s[2])), hi = fmax(s[0], fmax(s[1], s[2]));
    mjtNum mid = s[0] + s[1] + s[2] - lo - hi;
    if (h->has_slender && on_hull && !(lo < 0.2 * mid)) h->kutta_geom[h->nkutta++] = g;
  }
  h->fk_body = (int*)malloc(sizeof(int) * (m->nbody + 1));
  for (int b = 1; b < m->nbody; b++) {
    if (m->body_gravcomp[b] > 0 && in_subtree(m, b, fb)) h->fk_body[h->nfk++] = b;
  }

  // plates
  snprintf(full, NAME_LEN, "%shydro_foils", prefix);
  int tid = mj_name2id(m, mjOBJ_TEXT, full);
  const mjtNum* cla = numeric(m, prefix, "hydro_foil_cla", &size);
  int cla_size = size;
  if (tid >= 0) {
    char buf[4096];
    int count = text_names(m, tid, buf, (int)sizeof(buf));
    if (!cla || cla_size != count) {
      hydro_free(h);
      return fail(iname, "'<prefix>hydro_foil_cla' must give one C_La per '<prefix>hydro_foils'");
    }
    int drag_size = 0;
    const mjtNum* fd = numeric(m, prefix, "hydro_foil_drag", &drag_size);
    if (fd && drag_size != 3 * count) {
      hydro_free(h);
      return fail(iname, "'<prefix>hydro_foil_drag' must give C_D0 k_i C_N per '<prefix>hydro_foils'");
    }
    h->foil_geom = (int*)malloc(sizeof(int) * (count + 1));
    h->foil_k = (mjtNum*)malloc(sizeof(mjtNum) * (count + 1));
    h->foil_normal = (int*)malloc(sizeof(int) * (count + 1));
    h->foil_drag = (mjtNum*)calloc(3 * (count + 1), sizeof(mjtNum));
    h->panel = (mjtNum*)calloc(3 * NPANEL * (count + 1), sizeof(mjtNum));
    char* save = NULL;
    int i = 0;
    for (char* tok = strtok_r(buf, " \t\n", &save); tok; tok = strtok_r(NULL, " \t\n", &save)) {
      snprintf(full, NAME_LEN, "%s%s", prefix, tok);
      int g = mj_name2id(m, mjOBJ_GEOM, full);
      if (g < 0) {
        hydro_free(h);
        return fail(iname, "a geom of '<prefix>hydro_foils' is not in the model");
      }
      const mjtNum* s = m->geom_size + 3 * g;
      int normal = (s[1] <= s[2]) ? 1 : 2;
      if (s[0] < s[normal]) {
        hydro_free(h);
        return fail(iname, "a plate's chord must be along its geom's x axis");
      }
      h->foil_geom[i] = g;
      h->foil_normal[i] = normal;
      const mjtNum area = mjPI * s[0] * s[3 - normal];
      h->foil_k[i] = 0.5 * h->rho * area * cla[i];
      if (fd) {
        h->foil_drag[3 * i] = 0.5 * h->rho * area * fd[3 * i];
        h->foil_drag[3 * i + 1] = 0.5 * h->rho * area * fd[3 * i + 1] * cla[i] * cla[i];
        h->foil_drag[3 * i + 2] = 0.5 * h->rho * fd[3 * i + 2];
      }
      // normal-force panels of the ellipse: NSPAN span stations eta_j = cos(j pi / (NSPAN + 1))
      // with the Gauss-Chebyshev weights of the second kind, which integrate sqrt(1 - eta^2) f(eta)
      // (the chord's distribution times f) exactly for polynomials f of degree < 2 NSPAN: strip
      // j holds the area fraction 2 sin^2(j pi / (NSPAN + 1)) / (NSPAN + 1) of the ellipse, its
      // chord 2 a sin(j pi / (NSPAN + 1)) cut into NCHORD equal panels
      mjtNum* pn = h->panel + 3 * NPANEL * i;
      for (int j = 1; j <= NSPAN; j++) {
        mjtNum th = j * mjPI / (NSPAN + 1);
        mjtNum half = sin(th);
        for (int k = 0; k < NCHORD; k++) {
          mjtNum xi = -1.0 + (2.0 * k + 1.0) / NCHORD;
          pn[0] = xi * half * s[0];
          pn[1] = cos(th) * s[3 - normal];
          pn[2] = -h->foil_drag[3 * i + 2] * (area * 2.0 * half * half / (NSPAN + 1) / NCHORD);
          pn += 3;
        }
      }
      h->kutta_geom[h->nkutta++] = g;
      i++;
    }
    h->nfoil = count;
  }
  zero_model_terms(m, h);
  d->plugin_data[instance] = (uintptr_t)h;
  return 0;
}

static void hydro_destroy(mjData* d, int instance) {
  hydro_free((Hydro*)d->plugin_data[instance]);
  d->plugin_data[instance] = 0;
}

static void hydro_copy_cb(mjData* dest, const mjModel* m, const mjData* src, int instance) {
  Hydro* s = (Hydro*)src->plugin_data[instance];
  if (dest->plugin_data[instance]) hydro_free((Hydro*)dest->plugin_data[instance]);
  dest->plugin_data[instance] = s ? (uintptr_t)hydro_copy(s) : 0;
}

static void hydro_reset(const mjModel* m, mjtNum* state, void* data, int instance) {
  for (int k = 0; k < NSTATE; k++) state[k] = 0;
  Hydro* h = (Hydro*)data;
  if (h) h->have_last = 0;
}

static int hydro_nstate(const mjModel* m, int instance) { return NSTATE; }

static inline void cross3(mjtNum r[3], const mjtNum a[3], const mjtNum b[3]) {
  r[0] = a[1] * b[2] - a[2] * b[1];
  r[1] = a[2] * b[0] - a[0] * b[2];
  r[2] = a[0] * b[1] - a[1] * b[0];
}

// semi-axes of a geom's fluid ellipsoid, as MuJoCo's ellipsoid model takes them
static void semi_axes(mjtNum r[3], const mjModel* m, int g) {
  const mjtNum* s = m->geom_size + 3 * g;
  switch (m->geom_type[g]) {
    case mjGEOM_SPHERE:
      r[0] = r[1] = r[2] = s[0];
      break;
    case mjGEOM_CAPSULE:
      r[0] = r[1] = s[0];
      r[2] = s[1] + s[0];
      break;
    case mjGEOM_CYLINDER:
      r[0] = r[1] = s[0];
      r[2] = s[1];
      break;
    default:  // ellipsoid, box
      r[0] = s[0];
      r[1] = s[1];
      r[2] = s[2];
  }
}

// MuJoCo's translational drag of an ellipsoid (blunt, slender, Stokes), geom frame
static void ellipsoid_drag(mjtNum f[3], const mjtNum u[3], const mjtNum r[3], mjtNum blunt,
                           mjtNum slender, mjtNum rho, mjtNum beta) {
  mjtNum speed = mju_norm3(u);
  mjtNum lo = fmin(r[0], fmin(r[1], r[2])), hi = fmax(r[0], fmax(r[1], r[2]));
  mjtNum mid = r[0] + r[1] + r[2] - lo - hi;
  mjtNum a_max = mjPI * hi * mid;
  mjtNum a_proj = 0;
  if (speed > 0) {
    mjtNum x = u[0] / speed, y = u[1] / speed, z = u[2] / speed;
    mjtNum r2[3] = {r[0] * r[0], r[1] * r[1], r[2] * r[2]};
    mjtNum num = r2[1] * r2[1] * r2[2] * r2[2] * x * x + r2[2] * r2[2] * r2[0] * r2[0] * y * y
                 + r2[0] * r2[0] * r2[1] * r2[1] * z * z;
    mjtNum den = r2[1] * r2[2] * x * x + r2[2] * r2[0] * y * y + r2[0] * r2[1] * z * z;
    a_proj = den > 0 ? mjPI * sqrt(num / den) : 0;
  }
  mjtNum c = -rho * (blunt * a_proj + slender * (a_max - a_proj)) * speed
             - 6.0 * mjPI * (r[0] + r[1] + r[2]) / 3.0 * beta;
  f[0] = c * u[0];
  f[1] = c * u[1];
  f[2] = c * u[2];
}

// the wrenches of one evaluation, summed per weld body (a body without joints moves with its
// parent: the same Jacobian at any point) and applied once per weld body at the end, which saves
// most of the mj_applyFT calls (a Jacobian each): add force f (N, world) and moment t (N m,
// world) acting at point p (m, world) on body b
static void add_wrench(Hydro* h, const mjModel* m, const mjData* d, int b, const mjtNum f[3],
                       const mjtNum t[3], const mjtNum p[3]) {
  const int w = m->body_weldid[b];
  mjtNum* a = h->acc + 6 * w;
  if (!h->acc_on[w]) {
    h->acc_on[w] = 1;
    h->acc_list[h->nacc++] = w;
    for (int k = 0; k < 6; k++) a[k] = 0;
  }
  mjtNum arm[3], ta[3];
  for (int k = 0; k < 3; k++) arm[k] = p[k] - d->xipos[3 * w + k];
  cross3(ta, arm, f);
  for (int k = 0; k < 3; k++) {
    a[k] += f[k];
    a[3 + k] += t[k] + ta[k];
  }
}

// qfrc += Jp^T f + Jr^T t: force f (N, world) and moment t (N m, world) at point p (m, world) on
// body b, as mj_applyFT adds them with dense Jacobians, written for the dofs of b's chain alone
// (its other columns are zero): mj_jac's columns, Jr = the dof's axis cdof[0:3] and Jp =
// cdof[3:6] + cdof[0:3] x (p - the subtree's centre of mass), and mju_mulMatTVec's sums (a zero
// component of f or t skipped), in the same order, which gives the same numbers without the two
// 3 x nv Jacobians, their zeroing and the passes over every dof
static void apply_ft_chain(const mjModel* m, const mjData* d, const mjtNum f[3], const mjtNum t[3],
                           const mjtNum p[3], int b, mjtNum* qfrc) {
  const mjtNum* com = d->subtree_com + 3 * m->body_rootid[b];
  const mjtNum o0 = p[0] - com[0], o1 = p[1] - com[1], o2 = p[2] - com[2];
  const int wb = m->body_weldid[b];
  if (!m->body_dofnum[wb]) return;
  for (int da = m->body_dofadr[wb] + m->body_dofnum[wb] - 1; da >= 0; da = m->dof_parentid[da]) {
    const mjtNum* c = d->cdof + 6 * da;
    const mjtNum jp0 = c[3] + (c[1] * o2 - c[2] * o1);
    const mjtNum jp1 = c[4] + (c[2] * o0 - c[0] * o2);
    const mjtNum jp2 = c[5] + (c[0] * o1 - c[1] * o0);
    mjtNum q = 0;
    if (f[0] != 0) q += jp0 * f[0];
    if (f[1] != 0) q += jp1 * f[1];
    if (f[2] != 0) q += jp2 * f[2];
    qfrc[da] += q;
    q = 0;
    if (t[0] != 0) q += c[0] * t[0];
    if (t[1] != 0) q += c[1] * t[1];
    if (t[2] != 0) q += c[2] * t[2];
    qfrc[da] += q;
  }
}

static void apply_wrenches(Hydro* h, const mjModel* m, mjData* d, mjtNum* qfrc) {
  // a model whose Jacobians are sparse (nv >= 60 by default: scenes of several vehicles) takes
  // mj_applyFT itself, whose sparse sums this does not repeat
  const int sparse = mj_isSparse(m);
  for (int i = 0; i < h->nacc; i++) {
    const int w = h->acc_list[i];
    if (sparse) {
      mj_applyFT(m, d, h->acc + 6 * w, h->acc + 6 * w + 3, d->xipos + 3 * w, w, qfrc);
    } else {
      apply_ft_chain(m, d, h->acc + 6 * w, h->acc + 6 * w + 3, d->xipos + 3 * w, w, qfrc);
    }
    h->acc_on[w] = 0;
  }
  h->nacc = 0;
}

// MuJoCo's ellipsoid fluid model of one geom without its virtual-mass terms (MuJoCo documentation,
// "Fluid forces"; the plugin's added mass replaces them), in the geom's frame: om and u are the
// geom's angular velocity (rad/s) and its velocity through the water at its centre (m/s), r its
// semi-axes (m), c its fluidcoef (blunt drag, slender drag, angular drag, Kutta lift, Magnus lift);
// adds the torque (N m) to t and the force (N) to f:
//   Stokes drag      -3 pi D mu u and -pi D^3 mu om, D = 2 (r0 + r1 + r2) / 3;
//   quadratic drag   -rho |u| (C_blunt A_proj + C_slender (A_max - A_proj)) u, A_proj the area
//                    the ellipsoid shows to u, A_max = pi r_max r_mid;
//   angular drag     -rho |m| om, m_i = om_i (C_ang I_i + C_slender (I_max - I_i)),
//                    I_i = 8/15 pi r_i max(r_j, r_k)^4, I_max = 8/15 pi r_mid r_max^4;
//   Kutta lift       rho C_K cos(a) A_proj ((n x u) x u), n = ((r1 r2)^2 u0, (r2 r0)^2 u1,
//                    (r0 r1)^2 u2) the (unnormalised) normal of the projected section;
//   Magnus lift      rho C_M V (om x u), V = 4/3 pi r0 r1 r2.
static void ellipsoid_model(mjtNum t[3], mjtNum f[3], const mjtNum om[3], const mjtNum u[3],
                            const mjtNum r[3], const mjtNum c[5], mjtNum rho, mjtNum mu) {
  if (c[0] == 0 && c[1] == 0 && c[2] == 0 && c[3] == 0 && c[4] == 0) {
    // all five coefficients zero (the markers, and the plates, whose drag is the plate model's):
    // the quadratic and angular drag below are rho |u| (0 + 0) and rho |m| with m = 0, exact
    // zeros added to the Stokes terms, and there is no lift; the Stokes drag alone gives the
    // same numbers
    const mjtNum d_eq = 2.0 / 3.0 * (r[0] + r[1] + r[2]);
    const mjtNum drag_lin = mu * 3.0 * mjPI * d_eq;
    const mjtNum drag_ang = mu * mjPI * d_eq * d_eq * d_eq;
    for (int i = 0; i < 3; i++) {
      t[i] -= drag_ang * om[i];
      f[i] -= drag_lin * u[i];
    }
    return;
  }
  const mjtNum lo = fmin(r[0], fmin(r[1], r[2])), hi = fmax(r[0], fmax(r[1], r[2]));
  const mjtNum mid = r[0] + r[1] + r[2] - lo - hi;
  const mjtNum a_max = mjPI * hi * mid;
  const mjtNum speed = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  // squared products of the other two semi-axes: the projection of the ellipsoid along u
  const mjtNum s0 = (r[1] * r[2]) * (r[1] * r[2]);
  const mjtNum s1 = (r[2] * r[0]) * (r[2] * r[0]);
  const mjtNum s2 = (r[0] * r[1]) * (r[0] * r[1]);
  const mjtNum den = s0 * s0 * u[0] * u[0] + s1 * s1 * u[1] * u[1] + s2 * s2 * u[2] * u[2];
  const mjtNum num = s0 * u[0] * u[0] + s1 * u[1] * u[1] + s2 * u[2] * u[2];
  const mjtNum a_proj = mjPI * sqrt(den / fmax(mjMINVAL, num));

  const mjtNum d_eq = 2.0 / 3.0 * (r[0] + r[1] + r[2]);
  const mjtNum drag_lin =
      mu * 3.0 * mjPI * d_eq + rho * speed * (a_proj * c[0] + c[1] * (a_max - a_proj));
  const mjtNum i_max = 8.0 / 15.0 * mjPI * mid * hi * hi * hi * hi;
  mjtNum mom[3];
  for (int i = 0; i < 3; i++) {
    mjtNum o = fmax(r[(i + 1) % 3], r[(i + 2) % 3]);
    mjtNum ii = 8.0 / 15.0 * mjPI * r[i] * o * o * o * o;
    mom[i] = om[i] * (c[2] * ii + c[1] * (i_max - ii));
  }
  const mjtNum drag_ang = mu * mjPI * d_eq * d_eq * d_eq
                          + rho * sqrt(mom[0] * mom[0] + mom[1] * mom[1] + mom[2] * mom[2]);
  for (int i = 0; i < 3; i++) {
    t[i] -= drag_ang * om[i];
    f[i] -= drag_lin * u[i];
  }
  if (c[3] != 0) {
    const mjtNum n[3] = {s0 * u[0], s1 * u[1], s2 * u[2]};
    const mjtNum cos_a = num / fmax(mjMINVAL, speed * den);
    const mjtNum k = c[3] * rho * cos_a * a_proj;
    mjtNum circ[3], fk[3];
    cross3(circ, n, u);
    for (int i = 0; i < 3; i++) circ[i] *= k;
    cross3(fk, circ, u);
    for (int i = 0; i < 3; i++) f[i] += fk[i];
  }
  if (c[4] != 0) {
    const mjtNum k = c[4] * rho * 4.0 / 3.0 * mjPI * r[0] * r[1] * r[2];
    mjtNum fm[3];
    cross3(fm, om, u);
    for (int i = 0; i < 3; i++) f[i] += k * fm[i];
  }
}

// the ellipsoid model of every fluid geom of the vehicle in its water w (world, m/s), into the
// per-body wrenches
static void ellipsoid_forces(const mjModel* m, const mjData* d, Hydro* h, const mjtNum w[3]) {
  for (int i = 0; i < h->nfluid; i++) {
    const int g = h->fluid_geom[i];
    const mjtNum* fl = m->geom_fluid + mjNFLUID * g;
    const mjtNum* Rg = d->geom_xmat + 9 * g;
    mjtNum vel[6], wl[3], u[3], semi[3], t[3] = {0, 0, 0}, f[3] = {0, 0, 0};
    mj_objectVelocity(m, d, mjOBJ_GEOM, g, vel, 1);  // (omega, v) at the geom centre, its frame
    mju_mulMatTVec3(wl, Rg, w);
    u[0] = vel[3] - wl[0];
    u[1] = vel[4] - wl[1];
    u[2] = vel[5] - wl[2];
    semi_axes(semi, m, g);
    ellipsoid_model(t, f, vel, u, semi, fl + 1, h->rho, h->mu);
    mjtNum fw[3], tw[3];
    mju_mulMatVec3(fw, Rg, f);
    mju_mulMatVec3(tw, Rg, t);
    for (int k = 0; k < 3; k++) {
      fw[k] *= fl[0];  // the geom's interaction coefficient (1)
      tw[k] *= fl[0];
    }
    add_wrench(h, m, d, m->geom_bodyid[g], fw, tw, d->geom_xpos + 3 * g);
  }
}

static void hydro_compute(const mjModel* m, mjData* d, int instance, int capability_bit) {
  Hydro* h = (Hydro*)d->plugin_data[instance];
  if (!h) return;
  zero_model_terms(m, h);  // again after mj_setConst, which recomputes the virtual masses
  const mjtNum* st = d->plugin_state + m->plugin_stateadr[instance];
  const mjtNum rho = h->rho;
  mjtNum dt_w = d->time - st[6];
  mjtNum w[3] = {st[0] + st[3] * dt_w, st[1] + st[4] * dt_w, st[2] + st[5] * dt_w};
  const mjtNum* aw = st + 3;
  int accelerating = (aw[0] != 0 || aw[1] != 0 || aw[2] != 0);
  const mjtNum* R = d->xmat + 9 * h->free_body;  // world from body, row-major
  const mjtNum* qv = d->qvel + h->dof;
  mjtNum* qfrc = d->qfrc_passive;

  // velocity relative to the water, body frame: nu = (R^T (v - w), omega)
  mjtNum rel[3] = {qv[0] - w[0], qv[1] - w[1], qv[2] - w[2]};
  mjtNum nu[6];
  mju_mulMatTVec3(nu, R, rel);
  nu[3] = qv[3];
  nu[4] = qv[4];
  nu[5] = qv[5];

  // added mass in the mass matrix: [R A11 R^T, R A12; A21 R^T, A22]
  mjtNum blk[21];
  for (int e = 0; e < 21; e++) blk[e] = d->M[h->midx[e]];
  int fresh = !h->have_last;
  if (!fresh) {
    for (int e = 0; e < 21; e++) {
      if (blk[e] != h->last_blk[e]) {
        fresh = 1;
        break;
      }
    }
  }
  if (fresh) {
    mjtNum A11[9], A12[9], T11[9], tmp[9], T12[9];
    for (int i = 0; i < 3; i++) {
      for (int k = 0; k < 3; k++) {
        A11[3 * i + k] = h->MA[6 * i + k];
        A12[3 * i + k] = h->MA[6 * i + 3 + k];
      }
    }
    mju_mulMatMat(tmp, R, A11, 3, 3, 3);
    mju_mulMatMatT(T11, tmp, R, 3, 3, 3);
    mju_mulMatMat(T12, R, A12, 3, 3, 3);
    mjtNum T[36];
    for (int i = 0; i < 3; i++) {
      for (int k = 0; k < 3; k++) {
        T[6 * i + k] = T11[3 * i + k];
        T[6 * i + 3 + k] = T12[3 * i + k];
        T[6 * (3 + k) + i] = T12[3 * i + k];
        T[6 * (3 + i) + 3 + k] = h->MA[6 * (3 + i) + 3 + k];
      }
    }
    for (int e = 0; e < 21; e++) {
      blk[e] += T[6 * h->mrow[e] + h->mcol[e]];
      d->M[h->midx[e]] = blk[e];
      h->last_blk[e] = blk[e];
    }
    h->have_last = 1;
    mj_factorM(m, d);
  }

  // -C_B(nu) nu + M_A (omega x nu_1 + R^T a_water)
  mjtNum pl[6];
  mju_mulMatVec(pl, h->MB, nu, 6, 6);
  mjtNum ext[3];
  cross3(ext, nu + 3, nu);
  if (accelerating) {
    mjtNum ab[3];
    mju_mulMatTVec3(ab, R, aw);
    ext[0] += ab[0];
    ext[1] += ab[1];
    ext[2] += ab[2];
  }
  mjtNum f[3], t[3], c1[3], c2[3];
  cross3(f, pl, nu + 3);
  cross3(c1, pl, nu);
  cross3(c2, pl + 3, nu + 3);
  t[0] = c1[0] + c2[0];
  t[1] = c1[1] + c2[1];
  t[2] = c1[2] + c2[2];
  for (int i = 0; i < 3; i++) {
    f[i] += h->MA[6 * i] * ext[0] + h->MA[6 * i + 1] * ext[1] + h->MA[6 * i + 2] * ext[2];
    t[i] += h->MA[6 * (3 + i)] * ext[0] + h->MA[6 * (3 + i) + 1] * ext[1]
            + h->MA[6 * (3 + i) + 2] * ext[2];
  }
  const mjtNum u = nu[0], v = nu[1], ww = nu[2], p = nu[3], q = nu[4], r = nu[5];

  // crossflow elements: -1/2 rho C a |c| c
  for (int k = 0; k < h->ncross; k++) {
    const mjtNum* e = h->cross + 7 * k;
    mjtNum cy = v + r * e[0] - p * e[2];
    mjtNum cz = ww + p * e[1] - q * e[0];
    mjtNum c = sqrt(cy * cy + cz * cz);
    mjtNum gy = -0.5 * rho * e[3] * e[5] * c * cy;
    mjtNum gz = -0.5 * rho * e[4] * e[6] * c * cz;
    f[1] += gy;
    f[2] += gz;
    t[0] += e[1] * gz - e[2] * gy;
    t[1] -= e[0] * gz;
    t[2] += e[0] * gy;
  }
  t[0] -= h->roll_k * p * fabs(p);

  // slender-body lift, shed at the largest section; the afterbody's share of the Munk couple
  // (B22 - B11) u v (yaw), (B33 - B11) u w (pitch) is lost to the separation
  if (h->has_slender) {
    mjtNum uu = u > 0 ? u : 0;
    mjtNum ly = -rho * uu * h->slender[1] * (v + r * h->slender[0]);
    mjtNum lz = -rho * uu * h->slender[3] * (ww - q * h->slender[2]);
    f[1] += ly;
    f[2] += lz;
    t[2] += h->slender[0] * ly + h->slender[4] * (h->MB[7] - h->MB[0]) * uu * v;
    t[1] -= h->slender[2] * lz + h->slender[5] * (h->MB[14] - h->MB[0]) * uu * ww;
  }
  mjtNum fw[3];
  mju_mulMatVec3(fw, R, f);
  for (int i = 0; i < 3; i++) {
    qfrc[h->dof + i] += fw[i];
    qfrc[h->dof + 3 + i] += t[i];
  }

  // Froude-Krylov: rho V a on every displacing body
  mjtNum zero[3] = {0, 0, 0};
  if (accelerating) {
    for (int i = 0; i < h->nfk; i++) {
      int b = h->fk_body[i];
      mjtNum mb = m->body_gravcomp[b] * m->body_mass[b];
      mjtNum fb[3] = {mb * aw[0], mb * aw[1], mb * aw[2]};
      add_wrench(h, m, d, b, fb, zero, d->xipos + 3 * b);
    }
  }

  // segments' crossflow strips, each in its body's own frame with its own velocity
  for (int i = 0; i < h->nseg; i++) {
    int b = h->seg_body[i];
    const mjtNum* Rb = d->xmat + 9 * b;
    mjtNum vel[6], wl[3], ub[3];
    mj_objectVelocity(m, d, mjOBJ_XBODY, b, vel, 1);  // (omega, v) at the body origin, its frame
    mju_mulMatTVec3(wl, Rb, w);
    ub[0] = vel[3] - wl[0];
    ub[1] = vel[4] - wl[1];
    ub[2] = vel[5] - wl[2];
    mjtNum fs[3] = {0, 0, 0}, ts[3] = {0, 0, 0};
    for (int k = 0; k < h->nsegstrip; k++) {
      const mjtNum* e = h->seg_strip + 8 * k;
      if ((int)e[0] != i) continue;
      const mjtNum* r = e + 1;
      mjtNum wr[3];
      cross3(wr, vel, r);
      mjtNum cy = ub[1] + wr[1];
      mjtNum cz = ub[2] + wr[2];
      mjtNum c = sqrt(cy * cy + cz * cz);
      mjtNum gy = -0.5 * rho * e[4] * e[6] * c * cy;
      mjtNum gz = -0.5 * rho * e[5] * e[7] * c * cz;
      fs[1] += gy;
      fs[2] += gz;
      ts[0] += r[1] * gz - r[2] * gy;
      ts[1] -= r[0] * gz;
      ts[2] += r[0] * gy;
    }
    ts[0] -= h->seg_roll[i] * vel[0] * fabs(vel[0]);
    mjtNum fw2[3], tw2[3];
    mju_mulMatVec3(fw2, Rb, fs);
    mju_mulMatVec3(tw2, Rb, ts);
    add_wrench(h, m, d, b, fw2, tw2, d->xpos + 3 * b);
  }

  // plates: thin-plate drag (profile, induced, normal) and lift in the chord-normal plane
  for (int i = 0; i < h->nfoil; i++) {
    int g = h->foil_geom[i];
    const mjtNum* Rg = d->geom_xmat + 9 * g;
    mjtNum vel[6], wl[3], ul[3];
    mj_objectVelocity(m, d, mjOBJ_GEOM, g, vel, 1);
    mju_mulMatTVec3(wl, Rg, w);
    ul[0] = vel[3] - wl[0];
    ul[1] = vel[4] - wl[1];
    ul[2] = vel[5] - wl[2];
    int n = h->foil_normal[i];
    int span = 3 - n;
    mjtNum uc = ul[0], un = ul[n];
    mjtNum sp = sqrt(uc * uc + un * un);
    const mjtNum* fd = h->foil_drag + 3 * i;
    if (fd[0] != 0 || fd[1] != 0 || fd[2] != 0) {
      mjtNum fp[3] = {0, 0, 0}, tp[3] = {0, 0, 0};
      // profile drag of the in-plane velocity (chord and span)
      mjtNum ut = sqrt(uc * uc + ul[span] * ul[span]);
      fp[0] -= fd[0] * ut * uc;
      fp[span] -= fd[0] * ut * ul[span];
      // lift-induced drag against the chord-normal velocity: 1/2 rho S k_i (C_La uc un / sp)^2
      if (sp > 0) {
        mjtNum di = fd[1] * uc * uc * un * un / (sp * sp * sp);
        fp[0] -= di * uc;
        fp[n] -= di * un;
      }
      // normal force of each panel, at the panel: moment about the centre
      // (a panel at r = x e_x + s e_span: its normal velocity un + (omega x r)_n, its moment
      // r x (fn e_n); written out per normal axis, the terms of the cross products that are
      // products of the zero components of r and fn e_n left out, which changes no sum)
      if (fd[2] != 0) {
        const mjtNum* pn = h->panel + 3 * NPANEL * i;
        const mjtNum ox = vel[0], oy = vel[1], oz = vel[2];  // the geom's angular velocity
        if (n == 2) {  // normal z, span y: r = (x, y, 0)
          for (int k = 0; k < NPANEL; k++, pn += 3) {
            mjtNum unp = un + (ox * pn[1] - oy * pn[0]);
            mjtNum fn = pn[2] * fabs(unp) * unp;
            fp[2] += fn;
            tp[0] += pn[1] * fn;
            tp[1] -= pn[0] * fn;
          }
        } else {  // normal y, span z: r = (x, 0, z)
          for (int k = 0; k < NPANEL; k++, pn += 3) {
            mjtNum unp = un + (oz * pn[0] - ox * pn[1]);
            mjtNum fn = pn[2] * fabs(unp) * unp;
            fp[1] += fn;
            tp[0] -= pn[1] * fn;
            tp[2] += pn[0] * fn;
          }
        }
      }
      mjtNum fw2[3], tw2[3];
      mju_mulMatVec3(fw2, Rg, fp);
      mju_mulMatVec3(tw2, Rg, tp);
      add_wrench(h, m, d, m->geom_bodyid[g], fw2, tw2, d->geom_xpos + 3 * g);
    }
    if (sp <= 0) continue;
    mjtNum k = h->foil_k[i] * uc * un / sp;
    mjtNum fl[3] = {k * un, 0, 0};
    fl[n] = -k * uc;
    mjtNum fg[3], pt[3];
    mju_mulMatVec3(fg, Rg, fl);
    // at the quarter chord: half the chord semi-axis ahead of the centre (along the flow's x)
    mjtNum off = (uc > 0 ? 0.5 : -0.5) * m->geom_size[3 * g];
    for (int k = 0; k < 3; k++) pt[k] = d->geom_xpos[3 * g + k] + off * Rg[3 * k];
    add_wrench(h, m, d, m->geom_bodyid[g], fg, zero, pt);
  }

  // the ellipsoid model in this vehicle's own water, or (MuJoCo's fluid model on: its drag saw
  // option wind) the change of its drag in this vehicle's own water
  if (h->own_fluid) {
    ellipsoid_forces(m, d, h, w);
    apply_wrenches(h, m, d, qfrc);
    return;
  }
  const mjtNum* wind = m->opt.wind;
  if (h->ndrag && (w[0] != wind[0] || w[1] != wind[1] || w[2] != wind[2])) {
    for (int i = 0; i < h->ndrag; i++) {
      int g = h->drag_geom[i];
      const mjtNum* Rg = d->geom_xmat + 9 * g;
      const mjtNum* fc = m->geom_fluid + mjNFLUID * g;
      mjtNum vel[6], wl[3], wr[3], uo[3], ur[3], fo[3], fr[3], df[3], fg[3];
      mj_objectVelocity(m, d, mjOBJ_GEOM, g, vel, 1);
      mju_mulMatTVec3(wl, Rg, w);
      mju_mulMatTVec3(wr, Rg, wind);
      for (int k = 0; k < 3; k++) {
        uo[k] = vel[3 + k] - wl[k];
        ur[k] = vel[3 + k] - wr[k];
      }
      mjtNum semi[3];
      semi_axes(semi, m, g);
      ellipsoid_drag(fo, uo, semi, fc[1], fc[2], rho, h->mu);
      ellipsoid_drag(fr, ur, semi, fc[1], fc[2], rho, h->mu);
      for (int k = 0; k < 3; k++) df[k] = fo[k] - fr[k];
      mju_mulMatVec3(fg, Rg, df);
      add_wrench(h, m, d, m->geom_bodyid[g], fg, zero, d->geom_xpos + 3 * g);
    }
  }
  apply_wrenches(h, m, d, qfrc);
}

mjPLUGIN_LIB_INIT(bauv_hydro) {
  mjpPlugin plugin;
  mjp_defaultPlugin(&plugin);
  plugin.name = "bauv.hydro";
  plugin.capabilityflags = mjPLUGIN_PASSIVE;
  plugin.nattribute = 0;
  plugin.attributes = NULL;
  plugin.nstate = hydro_nstate;
  plugin.init = hydro_init;
  plugin.destroy = hydro_destroy;
  plugin.copy = hydro_copy_cb;
  plugin.reset = hydro_reset;
  plugin.compute = hydro_compute;
  mjp_registerPlugin(&plugin);
}
