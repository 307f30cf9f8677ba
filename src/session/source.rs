//! Which scene a request renders: a file or built-in scene, possibly as edited (its text sent
//! with the request), and building it, from the last scene's geometry when only the camera
//! changed.

use crate::scene::load::{base_dir, read_source, BuildOptions};
use crate::scene::{reload, Scene};
use std::sync::Arc;

/// A scene to render: what names it, the text to build it from if not the file's (or the
/// built-in's) own, and a count raised whenever a file it reads changed on disk, so that the
/// same text is built again (a changed OBJ or map).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneSource {
    /// A scene file path or a built-in scene's name (messages, file names, relative paths).
    pub spec: String,
    /// The scene's text as edited (None: read `spec`).
    pub text: Option<Arc<str>>,
    pub generation: u64,
}

impl From<&str> for SceneSource {
    fn from(spec: &str) -> Self {
        SceneSource {
            spec: spec.to_string(),
            text: None,
            generation: 0,
        }
    }
}

impl From<String> for SceneSource {
    fn from(spec: String) -> Self {
        SceneSource::from(spec.as_str())
    }
}

/// The folder relative paths in the scene `spec` start from (the current one for a built-in).
fn folder(spec: &str) -> Option<std::path::PathBuf> {
    let dir = base_dir(spec)
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or_else(|| ".".into());
    std::path::absolute(dir).ok()
}

/// The scene last built, with what it was built from.
pub(super) struct Built {
    pub source: SceneSource,
    /// The text it was built from (the file's when the source had none).
    pub text: Arc<str>,
    pub scene: Arc<Scene>,
}

impl Built {
    /// The scene `source` names: `prev` if it is the same source, else built, sharing `prev`'s
    /// geometry if only the camera changed (same scene file, same generation).
    pub fn scene_for(
        prev: Option<&Built>,
        source: &SceneSource,
        options: &BuildOptions,
    ) -> Result<Built, String> {
        if let Some(p) = prev.filter(|p| p.source == *source) {
            return Ok(Built {
                source: p.source.clone(),
                text: p.text.clone(),
                scene: p.scene.clone(),
            });
        }
        let text: Arc<str> = match &source.text {
            Some(t) => t.clone(),
            None => read_source(&source.spec)
                .map_err(|e| e.to_string())?
                .0
                .into(),
        };
        // The same text read from the same folder (a built-in written to ./<name>.toml): the
        // same scene, so the render goes on.
        if let Some(p) = prev.filter(|p| {
            p.source.generation == source.generation
                && *p.text == *text
                && folder(&p.source.spec) == folder(&source.spec)
        }) {
            return Ok(Built {
                source: source.clone(),
                text,
                scene: p.scene.clone(),
            });
        }
        let same_files = prev
            .filter(|p| p.source.spec == source.spec && p.source.generation == source.generation);
        let scene = reload::rebuild(
            same_files.map(|p| (&*p.scene, &*p.text)),
            &source.spec,
            &text,
            options,
        )
        .map_err(|e| e.to_string())?;
        Ok(Built {
            source: source.clone(),
            text,
            scene: Arc::new(scene),
        })
    }

    /// Whether the scene was built from text other than its file's (or built-in's) as it is
    /// on disk now: edits not written back.
    pub fn edited(&self) -> bool {
        read_source(&self.source.spec).map_or(true, |(disk, _)| *disk != *self.text)
    }
}
