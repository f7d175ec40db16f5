//! crest's integration tests as one binary (ripgrep style): one module per area, the
//! helpers in `util`. insta snapshots are in `snapshots/`; proptest keeps failure seeds in
//! `tests/proptest-regressions/<module>.txt` (its default for a crate root with a `main.rs`)
//! and replays them first.

mod architecture; // ARCHITECTURE.md's invariants read off the source: imports, rayon, files, sizes
mod atlas; // `crest atlas` (issue 33): patches placed every D mm, numbers against closed forms, shards, patches in the air
mod compare; // `crest compare` (issue 34 §2): registration of rotated, shifted, tilted, noisy maps; a map against itself; exit codes
mod convert;
mod cutters; // general cutters (issue 23): round inserts, APT, profiles, circle segments, axial run-out // `crest convert` and `crest inspect`: CLSF ↔ contact12 round trips, located errors
mod dialects;
mod endless; // endless and special inputs (issue 37): budgets per format, FIFOs and standard input read once // APT files of other CAM systems (samples/apt/), NX contact-contour data
mod fuzz_corpus; // the fuzz corpora replayed: every input returns (no panic, abort or hang)
mod gcode; // 5-axis G-code through the machine: CLSF → G-code → postures, simulate, inspect, errors
mod heightmap_io; // height-map files (CSV, XYZ, GSF, SDF): round trips, malformed files
mod hostile; // hostile input and lost data (issue 18): each reproduction, -o like coreutils, budgets
mod hostile2; // hostile input, second round (issue 37): limits on every route, CR line ends, located messages, escaped text
mod hostile3; // hostile input, third round (issue 37): failed commands change nothing, designs refused before their runs, no control characters on a terminal
mod install; // the version, completions, man pages and plain error lines of an installed crest
mod instruments; // the instruments' own height maps (issue 34): .sur, .al3d, .gwy, .plu, .plux, .opd, .vk4 written by hand, read exactly; truncations; exit 2; .datx refused
mod kinematics; // machines and feed planning (kinematics.md §8), `crest feed`, `--feed predicted`
mod measured_files; // studies and calibration on measured files (issue 34 §3): `measured_file` in a table, measured as `crest metrics` does, the calibration's factor
mod metrics; // profile and ISO 25178 parameters (iso25178.md §6 vectors), `crest metrics`
mod moves; // move kinds (issue 33): NX colours and feed changes, inspect counts and regions, patches in the air refused
mod parse; // reading and lowering CLSF and contact12: NX samples, own samples, properties
mod plot; // `crest plot`: every plot kind, titles and axis labels
mod process; // process effects: Brammertz limit of ploughing, calibration, run-out identification, Monte Carlo
mod profile_metrics; // `crest metrics PROFILE.csv` (issue 34): a measured x_mm,z_um profile against the closed forms of a sine
mod real_parts; // design surfaces: meshes, contact data from the part or the path, N-buffer, maps, real exports
mod report; // `crest report`: 002 Table 2, the crest and simulate models, committed reports
mod resample; // even feed per tooth and constant Δθ: properties, streaming, `crest resample`
mod runout_identify; // run-out identification that reproduces itself (issue 34 §4): a grid of teeth, offsets, phases, leads, noise; maps
mod sanity; // loud sanity checks (issue 33): heights beyond the bound, narrow patches, ap clipping the scallop, tools without corner, contradictory units
mod shard; // `crest study --shard K/N` in separate processes and `crest merge`: the single-process bytes
mod study; // `crest study`: designed experiments through the whole pipeline, their effects
mod surface; // z-map and N-buffer: closed forms, patches, R7 trials, properties, `crest simulate`
mod swept_reference; // the swept ball and bull nose on a freeform NX-style 5-axis export against a reference written in the test (issue 33)
mod synth; // `crest synth`: synthetic paths, exact stepovers, CLSF and contact12 outputs
mod tool; // cutters: model.md R1-R3, properties, `crest tool`, `crest runout`
mod util;
mod viewer; // `crest view`: the 3-D viewer page in headless Chromium, `simulate --view` // helpers written once: commands, paths, files, JSON/CSV outputs, passes, generators
mod x3p; // ISO 25178-72 `.x3p`: what surfalize reads, round trips, damaged files refused
