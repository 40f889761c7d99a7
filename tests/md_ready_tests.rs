//! The ready-made MD tests at small scale through the `ballast` binary:
//! `karrech deposit` + `karrech load` and `luding compress` + `luding cycle`.
//! The expected values are physics: at rest the base carries the spheres' weight,
//! servo walls hold their prescribed stress, and the cyclic stress reaches
//! `p₀ + Δσ` at mid-cycle.

use crate::scratch;

use std::path::Path;
use std::process::Command;

fn ballast(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_ballast")).args(args).output().unwrap();
    assert!(out.status.success(), "ballast {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).to_string()
}

/// Rows of a CSV file as (header, numbers).
fn csv(path: &Path) -> (Vec<String>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines.map(|l| l.split(',').map(|v| v.parse().unwrap_or(f64::NAN)).collect()).collect();
    (header, rows)
}

fn col(header: &[String], name: &str) -> usize {
    header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"))
}

#[test]
fn karrech_deposit_then_cyclic_load() {
    let dir = scratch::dir("karrech");
    let (dep, load) = (dir.join("deposit"), dir.join("load"));
    // 40 spheres of Table 1 sizes, softened (E = 10 MPa) so that a 2 µs step resolves contacts.
    ballast(
        &["karrech", "deposit", "--out", dep.to_str().unwrap(), "--spheres", "40", "--young", "1e7", "--dt", "2e-6"]
            .iter()
            .chain(&["--duration", "0.6", "--every", "1000", "--quiet"])
            .copied()
            .collect::<Vec<_>>(),
    );
    let scene = std::fs::read_to_string(dep.join("deposit.toml")).unwrap();
    assert_eq!(scene.matches("[[body]]").count(), 40);
    assert_eq!(scene.matches("[[symmetry]]").count(), 2);
    assert!(scene.contains("radius = 0.075"));
    for fig in ["fig3a_apparent_weight", "fig3b_coordination", "fig3c_packing_fraction", "fig3d_energies"] {
        assert!(dep.join(format!("{fig}.png")).exists() && dep.join(format!("{fig}.svg")).exists(), "{fig}");
    }
    // At rest, 40 spheres lie in one layer on the base of a quarter cylinder of
    // radius 75 mm: the base carries their weight but for what the cylinder's
    // friction holds, which needs spheres pressed against it (few here); the
    // kinetic energy left after 0.6 s is < 1e-5 of the potential. 3 %.
    let (h, rows) = csv(&dep.join("series.csv"));
    let last = rows.last().unwrap();
    let final_json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dep.join("final.json")).unwrap()).unwrap();
    let weight: f64 = final_json["bodies"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            let r = b["radius"].as_f64().unwrap();
            2710.0 * 4.0 / 3.0 * std::f64::consts::PI * r * r * r * 9.81
        })
        .sum();
    let base = last[col(&h, "base_force_N")];
    assert!((base - weight).abs() < 0.03 * weight, "base {base} N vs weight {weight} N");
    let phi = last[col(&h, "packing_fraction")];
    assert!(phi > 0.0 && phi < 0.74, "packing fraction {phi}");

    ballast(
        &["karrech", "load", "--from", dep.to_str().unwrap(), "--out", load.to_str().unwrap(), "--cycles", "2"]
            .iter()
            .chain(&["--every", "500", "--quiet"])
            .copied()
            .collect::<Vec<_>>(),
    );
    let (h, rows) = csv(&load.join("cycles.csv"));
    assert_eq!(rows.len(), 2, "one row per cycle");
    // Rows at t = k/f, f = 50 Hz, to within a step (2 µs).
    for (k, r) in rows.iter().enumerate() {
        assert!((r[col(&h, "time_s")] - (k + 1) as f64 / 50.0).abs() <= 2e-6 + 1e-12);
    }
    assert!(h.contains(&"plate_position_m".to_string()));
    assert!(load.join("residual_displacement.png").exists());

    // Accelerated (Karrech et al. Fig. 10): 1 initial cycle, windows of 2, jumps of 2.
    let acc = dir.join("accelerated");
    ballast(
        &["karrech", "load", "--from", dep.to_str().unwrap(), "--out", acc.to_str().unwrap(), "--cycles", "7"]
            .iter()
            .chain(&["--every", "500", "--quiet", "--accelerate", "1,2,2"])
            .copied()
            .collect::<Vec<_>>(),
    );
    let (h, rows) = csv(&acc.join("settlement.csv"));
    assert_eq!(rows.len(), 7, "one row per cycle");
    // Cycles 1, 2, 3 computed, 4-5 extrapolated, 6-7 computed.
    let computed: Vec<f64> = rows.iter().map(|r| r[col(&h, "computed")]).collect();
    assert_eq!(computed, [1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0]);
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(acc.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["computed_cycles"], 5);
    assert!(acc.join("settlement_accelerated.png").exists());
    let scene = std::fs::read_to_string(acc.join("load.toml")).unwrap();
    assert!(scene.contains("[settlement]") && scene.contains("settlement_body = \"plate\""));

    // Against a full run through the driver (a window longer than the run never
    // jumps): errors.csv. Cycles 2 and 3 are computed by both from the same
    // state, step for step, so their accrued error is exactly 0; after the jump
    // it is |s_acc − s_full| / |s_full − s_full(1)|.
    let full = dir.join("full");
    let args = ["--from", dep.to_str().unwrap(), "--cycles", "7", "--every", "500", "--quiet"];
    ballast(&[&["karrech", "load", "--out", full.to_str().unwrap()][..], &args, &["--accelerate", "1,8,1"]].concat());
    let referenced = dir.join("referenced");
    ballast(
        &[
            &["karrech", "load", "--out", referenced.to_str().unwrap()][..],
            &args,
            &["--accelerate", "1,2,2", "--reference", full.to_str().unwrap()],
        ]
        .concat(),
    );
    let (h, errors) = csv(&referenced.join("errors.csv"));
    let (hf, full_rows) = csv(&full.join("settlement.csv"));
    assert_eq!(errors.len(), 7);
    let s = col(&h, "settlement_m");
    let s_full = col(&h, "reference_settlement_m");
    let e = col(&h, "accrued_error");
    assert_eq!((errors[1][e], errors[2][e]), (0.0, 0.0));
    let base = full_rows[0][col(&hf, "settlement_m")];
    for row in &errors[3..] {
        let want = (row[s] - row[s_full]).abs() / (row[s_full] - base).abs();
        assert!((row[e] - want).abs() <= 1e-12 * want.max(1.0), "{row:?}");
    }
}

#[test]
fn luding_compression_then_one_cycle() {
    let dir = scratch::dir("luding");
    let (comp, cyc) = (dir.join("compress"), dir.join("cycle"));
    ballast(
        &[
            "luding",
            "compress",
            "--out",
            comp.to_str().unwrap(),
            "--spheres",
            "27",
            "--duration",
            "3",
            "--every",
            "2000",
        ]
        .iter()
        .chain(&["--quiet"])
        .copied()
        .collect::<Vec<_>>(),
    );
    // At equilibrium each wall holds p₀ = 1 kPa: the spheres' push over the face
    // area (from the wall positions). Walls at rest within E_k/E_p ≤ 1e-4: 2 %.
    let (h, rows) = csv(&comp.join("series.csv"));
    let last = rows.last().unwrap();
    let scene = std::fs::read_to_string(comp.join("compress.toml")).unwrap();
    assert!(scene.contains("equilibrium"));
    let l0 = {
        // The lattice box: 3 spheres a side at pitch 1.05 × the largest diameter.
        let final_scene = std::fs::read_to_string(comp.join("final_scene.toml")).unwrap();
        assert!(final_scene.contains("[[wall]]"));
        let f: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(comp.join("final.json")).unwrap()).unwrap();
        let r_max = f["bodies"].as_array().unwrap().iter().map(|b| b["radius"].as_f64().unwrap()).fold(0.0, f64::max);
        3.0 * 2.0 * r_max * 1.05
    };
    let l = |a: &str| l0 - last[col(&h, &format!("{a}0_position_m"))] - last[col(&h, &format!("{a}1_position_m"))];
    let (lx, ly, lz) = (l("x"), l("y"), l("z"));
    for (wall, area) in [("x0", ly * lz), ("x1", ly * lz), ("y0", lx * lz), ("z1", lx * ly)] {
        let s = last[col(&h, &format!("{wall}_force_N"))] / area;
        assert!((s - 1000.0).abs() < 20.0, "{wall}: {s} Pa");
    }

    ballast(
        &["luding", "cycle", "--from", comp.to_str().unwrap(), "--out", cyc.to_str().unwrap(), "--cycles", "1"]
            .iter()
            .chain(&["--every", "1000", "--quiet"])
            .copied()
            .collect::<Vec<_>>(),
    );
    let (h, rows) = csv(&cyc.join("loops.csv"));
    // σ_xx follows p₀ + Δσ(1 − cos 2πt/t₀)/2: 1200 Pa at t = 5 s; the walls lag the
    // stress by their relaxation time m/γ = 0.01 s ≪ 10 s, and the box keeps
    // σ_yy at p₀. 3 % (the spheres' own dynamics on 27 spheres).
    let mid = rows.iter().min_by(|a, b| (a[0] - 5.0).abs().total_cmp(&(b[0] - 5.0).abs())).unwrap();
    assert!((mid[col(&h, "sigma_xx_pa")] - 1200.0).abs() < 36.0, "σ_xx {}", mid[col(&h, "sigma_xx_pa")]);
    assert!((mid[col(&h, "sigma_yy_pa")] - 1000.0).abs() < 30.0, "σ_yy {}", mid[col(&h, "sigma_yy_pa")]);
    let (_, strain) = csv(&cyc.join("strain.csv"));
    assert_eq!(strain.len(), 1);
    assert!(cyc.join("stress_strain_loops.png").exists() && cyc.join("strain_accumulation.svg").exists());

    // Figs. 3–5 overlay runs: the same box cycled again, compared with the first.
    let again = dir.join("again");
    ballast(
        &["luding", "cycle", "--from", comp.to_str().unwrap(), "--out", again.to_str().unwrap(), "--cycles", "1"]
            .iter()
            .chain(&["--every", "1000", "--quiet"])
            .copied()
            .collect::<Vec<_>>(),
    );
    let cmp = dir.join("compare");
    ballast(&[
        "luding",
        "compare",
        "--runs",
        cyc.to_str().unwrap(),
        again.to_str().unwrap(),
        "--out",
        cmp.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(cmp.join("compare.csv")).unwrap();
    let rows: Vec<&str> = text.lines().skip(1).collect();
    assert_eq!(rows.len(), 2, "{text}");
    // Same scene, same seed: the same ε_N to the last digit, labelled with N = 27.
    let eps = |r: &str| r.rsplit(',').next().unwrap().to_string();
    assert_eq!(eps(rows[0]), eps(rows[1]));
    assert!(rows.iter().all(|r| r.contains(",27,0.1,1,")), "{text}");
    for f in ["strain_accumulation.png", "strain_accumulation.svg", "first_cycle_loops.png", "first_cycle_loops.svg"] {
        assert!(cmp.join(f).exists(), "{f}");
    }
    // A folder that is not a cycled run is refused with its name.
    let out = Command::new(env!("CARGO_BIN_EXE_ballast"))
        .args(["luding", "compare", "--runs", comp.to_str().unwrap(), "--out", cmp.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("not a `luding cycle` output"), "{err}");
}
