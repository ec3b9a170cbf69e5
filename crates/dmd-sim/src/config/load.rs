//! Reading a scene: the TOML text, its overrides, and the checks of every body kind, in one
//! place. `scene` knows the keys; each body kind's module knows its own checks; this module
//! is where a scene's body kind decides which of them run.

use std::path::{Path, PathBuf};

use crate::config::scene::{Scene, SceneError};
use crate::config::{limits, site_scene, smd_spec};

impl Scene {
    /// Reads and checks a scene file, applying `overrides` (`KEY=VALUE`) first.
    ///
    /// # Errors
    /// Any [`SceneError`]; the message names the file, the key and the problem.
    pub fn load(path: &Path, overrides: &[String]) -> Result<(Scene, PathBuf), SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_owned(),
            source,
        })?;
        let scene = Scene::from_str_with(&text, overrides)?;
        let base = path.parent().map(Path::to_owned).unwrap_or_default();
        Ok((scene, base))
    }

    /// Parses and checks scene text, applying `overrides` (`KEY=VALUE`) first.
    ///
    /// # Errors
    /// Any [`SceneError`].
    pub fn from_str_with(text: &str, overrides: &[String]) -> Result<Scene, SceneError> {
        let mut doc: toml::Table = text
            .parse()
            .map_err(|e: toml::de::Error| SceneError::Syntax(e.to_string().trim().to_owned()))?;
        for arg in overrides {
            Scene::apply_override(&mut doc, arg)?;
        }
        site_scene::check_document(&doc)?;
        let mut scene: Scene = serde_path_to_error::deserialize(toml::Value::Table(doc)).map_err(
            |e: serde_path_to_error::Error<toml::de::Error>| {
                let key = e.path().to_string();
                // toml appends its own `in `key`` line; the path above is more precise.
                let problem = e.inner().to_string();
                let problem = problem
                    .split("\nin `")
                    .next()
                    .unwrap_or("")
                    .trim()
                    .to_owned();
                SceneError::Key { key, problem }
            },
        )?;
        site_scene::fill_masses(&mut scene);
        scene.check()?;
        scene.check_sweep_points(text, overrides)?;
        Ok(scene)
    }

    /// The scene of one point of a `[sweep]`: the key set to value `k`, the sweep
    /// and chains tables removed.
    ///
    /// # Errors
    /// The point's [`SceneError`], under the key `sweep.values[k]`.
    pub fn sweep_point(
        &self,
        text: &str,
        overrides: &[String],
        k: usize,
    ) -> Result<Scene, SceneError> {
        let Some(sw) = &self.sweep else {
            return Ok(self.clone());
        };
        let mut o = overrides.to_vec();
        o.push(format!("{}={}", sw.key, sw.values[k]));
        o.push("sweep=".to_owned());
        if self.chains.is_some() {
            o.push("chains=".to_owned());
        }
        Scene::from_str_with(text, &o).map_err(|e| {
            SceneError::invalid(
                format!("sweep.values[{k}]"),
                format!("with {} = {}: {e}", sw.key, sw.values[k]),
            )
        })
    }

    /// Every point of a sweep must be a valid scene.
    fn check_sweep_points(&self, text: &str, overrides: &[String]) -> Result<(), SceneError> {
        if let Some(sw) = &self.sweep {
            for k in 0..sw.values.len() {
                self.sweep_point(text, overrides, k)?;
            }
        }
        Ok(())
    }

    /// Every check of a parsed scene, in the order that decides which error a bad scene
    /// reports: species, the body kind's tables, the rest, the output limits, the standard-MD
    /// engine's keys, ensembles.
    fn check(&self) -> Result<(), SceneError> {
        self.check_species()?;
        // The body kind's keys and tables.
        crate::config::plan::check_bodies(self)?;
        self.check_rest()?;
        limits::check(self)?;
        smd_spec::check(self)?;
        self.check_issue_9()
    }
}
