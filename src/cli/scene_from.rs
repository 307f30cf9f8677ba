//! `ptui scene --from model.glb -o scene.toml`: write the scene ptui makes for a bare model
//! (`scene::model`), for editing. The mesh path is written relative to the scene file where the
//! model sits in the same folder, else absolute.

use anyhow::Context;
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct SceneArgs {
    /// The model: an OBJ (with its .mtl), a .gltf or a .glb.
    #[arg(long)]
    pub from: PathBuf,
    /// The scene file to write (atomically).
    #[arg(short, long)]
    pub output: PathBuf,
}

pub fn run(args: &SceneArgs) -> anyhow::Result<()> {
    if !crate::scene::model::is_model(&args.from) {
        anyhow::bail!(
            "{}: not a model file (.obj, .gltf or .glb)",
            args.from.display()
        );
    }
    let written = relative_to(&args.from, &args.output);
    let text = crate::scene::model::scene_text(&args.from, &written).map_err(anyhow::Error::msg)?;
    crate::io::output::write_atomic(&args.output, text.as_bytes())
        .with_context(|| format!("{}: cannot write the scene", args.output.display()))?;
    println!("wrote {}", args.output.display());
    Ok(())
}

/// `model` as the scene file `scene` names it.
fn relative_to(model: &Path, scene: &Path) -> String {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let (model, scene) = (abs(model), abs(scene));
    match (model.parent(), scene.parent(), model.file_name()) {
        (Some(a), Some(b), Some(name)) if a == b => name.to_string_lossy().into_owned(),
        _ => model.display().to_string(),
    }
}
