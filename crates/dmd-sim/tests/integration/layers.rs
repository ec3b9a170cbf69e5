//! The layers of `dmd-sim` as invariants of its source: engine ← models ← analysis ← config ←
//! driver. A module imports only from its own layer or those before it, no two modules import
//! each other (directly or round a cycle), a body model never imports another model, and only
//! `config` reads TOML. Tests (`#[cfg(test)]` modules) may reach anywhere.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const LAYERS: [&str; 5] = ["engine", "models", "analysis", "config", "driver"];

/// The shared modules of `models`; every other module there is a body model, which may use the
/// engine and these, not another model.
const SHARED: [&str; 4] = ["molecule", "rotor", "search", "site_pairs"];

fn is_model(name: &str) -> bool {
    !SHARED.contains(&name)
}

/// Module path (relative to `src`, without `.rs`, `mod` dropped) of every source file but the
/// binaries and `lib.rs`.
fn modules(src: &Path) -> BTreeMap<Vec<String>, PathBuf> {
    fn walk(dir: &Path, src: &Path, out: &mut BTreeMap<Vec<String>, PathBuf>) {
        for e in std::fs::read_dir(dir).expect("src readable") {
            let p = e.expect("entry").path();
            if p.is_dir() {
                walk(&p, src, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let rel = p.strip_prefix(src).expect("under src").with_extension("");
                let mut parts: Vec<String> = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect();
                if parts[0] == "bin" || parts == ["lib"] {
                    continue;
                }
                if parts.last().is_some_and(|l| l == "mod") {
                    parts.pop();
                }
                out.insert(parts, p);
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(src, src, &mut out);
    out
}

/// The text before the first `#[cfg(test)]`: what the library itself compiles.
fn library_part(text: &str) -> &str {
    text.split("#[cfg(test)]").next().unwrap_or("")
}

/// Every `crate::a::b::…` path in `text` (in `use` lists, expressions and doc links), split
/// into its segments; `use crate::x::{a, b::c}` gives `x::a` and `x::b::c`.
fn crate_paths(text: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(k) = rest.find("crate::") {
        let after = &rest[k + "crate::".len()..];
        let prefix_ok = k == 0
            || !rest[..k]
                .chars()
                .next_back()
                .is_some_and(|c| c.is_alphanumeric() || c == '_' || c == ':');
        rest = after;
        if !prefix_ok {
            continue;
        }
        let mut segs = Vec::new();
        let mut s = after;
        loop {
            let end = s
                .find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(s.len());
            if end == 0 {
                break;
            }
            segs.push(s[..end].to_owned());
            s = &s[end..];
            if let Some(t) = s.strip_prefix("::") {
                s = t;
                if let Some(group) = s.strip_prefix('{') {
                    // A use list: one path per top-level item.
                    let close = matching_brace(group);
                    for item in split_top(&group[..close]) {
                        let mut p = segs.clone();
                        p.extend(
                            item.split("::")
                                .map(|x| x.trim().to_owned())
                                .filter(|x| !x.is_empty() && x != "self" && x != "*")
                                .take_while(|x| !x.starts_with('{')),
                        );
                        out.push(p);
                    }
                    segs.clear();
                    break;
                }
            } else {
                break;
            }
        }
        if !segs.is_empty() {
            out.push(segs);
        }
    }
    out
}

fn matching_brace(s: &str) -> usize {
    let mut depth = 0;
    for (k, c) in s.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => return k,
            '}' => depth -= 1,
            _ => {}
        }
    }
    s.len()
}

fn split_top(s: &str) -> Vec<String> {
    let (mut out, mut cur, mut depth) = (Vec::new(), String::new(), 0);
    for c in s.chars() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                out.push(std::mem::take(&mut cur));
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    out.push(cur);
    out.into_iter()
        .map(|x| x.split_whitespace().collect())
        .collect()
}

/// The longest module prefix of `path` among `mods`.
fn resolve(path: &[String], mods: &BTreeMap<Vec<String>, PathBuf>) -> Option<Vec<String>> {
    (1..=path.len())
        .rev()
        .map(|k| path[..k].to_vec())
        .find(|p| mods.contains_key(p))
}

fn rank(module: &[String]) -> usize {
    LAYERS
        .iter()
        .position(|l| *l == module[0])
        .unwrap_or_else(|| panic!("module {} is in no layer", module.join("::")))
}

/// File-level import edges of the library code.
fn edges(src: &Path) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mods = modules(src);
    let mut out = BTreeMap::new();
    for (m, file) in &mods {
        let text = std::fs::read_to_string(file).expect("readable");
        let mut targets = BTreeSet::new();
        for p in crate_paths(library_part(&text)) {
            if let Some(t) = resolve(&p, &mods)
                && &t != m
            {
                targets.insert(t);
            }
        }
        // `super::x` inside a nested module.
        for line in library_part(&text).lines() {
            if let Some(rest) = line.trim().strip_prefix("use super::") {
                let mut p = m[..m.len() - 1].to_vec();
                p.extend(
                    rest.trim_end_matches(';')
                        .split("::")
                        .map(|x| x.trim_matches(|c| c == '{' || c == '}').to_owned())
                        .take(1),
                );
                if let Some(t) = resolve(&p, &mods)
                    && &t != m
                {
                    targets.insert(t);
                }
            }
        }
        out.insert(m.clone(), targets);
    }
    out
}

fn src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn show(m: &[String]) -> String {
    m.join("::")
}

#[test]
fn every_module_is_in_a_layer_and_imports_only_downwards() {
    let mut wrong = Vec::new();
    for (m, targets) in edges(&src_dir()) {
        for t in targets {
            if rank(&t) > rank(&m) {
                wrong.push(format!("{} → {}", show(&m), show(&t)));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "imports against the layer order (engine ← models ← analysis ← config ← driver):\n{}",
        wrong.join("\n")
    );
}

#[test]
fn no_import_cycle_between_modules() {
    let g = edges(&src_dir());
    // Depth-first search with colours; a grey target is a back edge: a cycle.
    fn visit(
        v: &Vec<String>,
        g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        colour: &mut BTreeMap<Vec<String>, u8>,
        stack: &mut Vec<Vec<String>>,
    ) -> Option<Vec<Vec<String>>> {
        colour.insert(v.clone(), 1);
        stack.push(v.clone());
        for w in &g[v] {
            match colour.get(w).copied().unwrap_or(0) {
                1 => {
                    let from = stack.iter().position(|x| x == w).expect("on the stack");
                    return Some(stack[from..].to_vec());
                }
                0 => {
                    if let Some(c) = visit(w, g, colour, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        colour.insert(v.clone(), 2);
        None
    }
    let mut colour = BTreeMap::new();
    for v in g.keys() {
        if colour.get(v).copied().unwrap_or(0) == 0
            && let Some(c) = visit(v, &g, &mut colour, &mut Vec::new())
        {
            panic!(
                "import cycle: {} → {}",
                c.iter().map(|m| show(m)).collect::<Vec<_>>().join(" → "),
                show(&c[0])
            );
        }
    }
}

#[test]
fn a_body_model_never_imports_another_model() {
    let mut wrong = Vec::new();
    for (m, targets) in edges(&src_dir()) {
        if m.len() < 2 || m[0] != "models" || !is_model(&m[1]) {
            continue;
        }
        for t in targets {
            if t.len() > 1 && t[0] == "models" && is_model(&t[1]) && t[1] != m[1] {
                wrong.push(format!("{} → {}", show(&m), show(&t)));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "models importing models:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn only_config_reads_toml() {
    let mut wrong = Vec::new();
    for (m, file) in modules(&src_dir()) {
        let text = std::fs::read_to_string(&file).expect("readable");
        if m[0] != "config" && library_part(&text).contains("toml::") {
            wrong.push(show(&m));
        }
    }
    assert!(
        wrong.is_empty(),
        "modules outside config using toml: {wrong:?}"
    );
}

/// The kinds of smooth potential are plug-ins: only `scene` (the keys and `describe`) and the
/// kinds' own modules (`visit`, each kind's `select`) name a `PotentialSpec` variant, so a new
/// kind changes nothing else.
#[test]
fn only_the_kinds_branch_on_the_kind_of_potential() {
    let mut wrong = Vec::new();
    for (m, file) in modules(&src_dir()) {
        let text = std::fs::read_to_string(&file).expect("readable");
        let own = m == ["config", "scene"] || m.starts_with(&["config".into(), "kinds".into()]);
        if !own && library_part(&text).contains("PotentialSpec::") {
            wrong.push(show(&m));
        }
    }
    assert!(
        wrong.is_empty(),
        "modules outside config::scene and config::kinds naming a kind: {wrong:?}"
    );
}

/// The body kinds are decided in one place: only `config::plan` names a `Plan` variant (the
/// driver asks the plan what it needs of a body kind and receives the model as a type), so a
/// new body model adds a variant there and its own model and scene modules, nothing else.
#[test]
fn only_the_plan_branches_on_the_body_kind() {
    let mut wrong = Vec::new();
    for (m, file) in modules(&src_dir()) {
        let text = std::fs::read_to_string(&file).expect("readable");
        let part = library_part(&text);
        let names_a_variant = ["Spheres", "Terraced", "Sites", "Flexible"]
            .iter()
            .any(|v| part.contains(&format!("Plan::{v}")));
        if m != ["config", "plan"] && names_a_variant {
            wrong.push(show(&m));
        }
    }
    assert!(
        wrong.is_empty(),
        "modules outside config::plan naming a body kind: {wrong:?}"
    );
}

#[test]
fn the_checks_see_the_edges_they_judge() {
    // The parser itself: use lists, nested groups, inline paths and doc links.
    let text = "use crate::engine::model::{PairModel, Report};\n\
                use crate::config::{load, scene::Scene};\n\
                let x = crate::driver::run::Quiet;\n\
                /// [`a`](crate::analysis::output::short)\n\
                #[cfg(test)] use crate::driver::hmc::Chain;";
    let paths: Vec<String> = crate_paths(library_part(text))
        .iter()
        .map(|p| p.join("::"))
        .collect();
    assert_eq!(
        paths,
        [
            "engine::model::PairModel",
            "engine::model::Report",
            "config::load",
            "config::scene::Scene",
            "driver::run::Quiet",
            "analysis::output::short",
        ]
    );
    // The real graph has the edges everyone knows of.
    let g = edges(&src_dir());
    let m = |s: &str| s.split("::").map(str::to_owned).collect::<Vec<_>>();
    assert!(g[&m("driver::run")].contains(&m("engine::simulation")));
    assert!(g[&m("models::terraced")].contains(&m("engine::model")));
    assert!(g[&m("config::load")].contains(&m("config::site_scene")));
    assert!(g.len() >= 40, "{} modules found", g.len());
}
