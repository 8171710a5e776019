//! `ductile info MESH`: statistics of a mesh file.

use std::io::Write;

use ductile_io::MeshRef;

/// Arguments of `ductile info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The mesh file (`.glb`, `.gltf`, `.obj`), optionally with `#name` selecting one OBJ
    /// object/group or glTF mesh.
    pub mesh: String,
}

/// Runs the command.
pub fn run(args: &Args, out: &mut dyn Write) -> anyhow::Result<u8> {
    let r = MeshRef::parse(&args.mesh);
    let rest = ductile_io::load_rest_mesh(&r)?;
    let mesh = rest.mesh();
    let topo = rest.topology();
    writeln!(out, "{r}")?;
    writeln!(out, "  stored vertices: {}", topo.stored_count())?;
    writeln!(out, "  welded vertices: {}", topo.vertex_count())?;
    writeln!(
        out,
        "  triangles:       {} ({} after welding)",
        mesh.triangle_count(),
        topo.triangles.len()
    )?;
    writeln!(
        out,
        "  normals: {}, uvs: {}",
        if mesh.normals.is_some() { "yes" } else { "no" },
        if mesh.uvs.is_some() { "yes" } else { "no" }
    )?;
    if let Some((lo, hi)) = mesh.bounds() {
        writeln!(
            out,
            "  bounds: min ({:.4}, {:.4}, {:.4}), max ({:.4}, {:.4}, {:.4}), size ({:.4}, {:.4}, {:.4})",
            lo.x,
            lo.y,
            lo.z,
            hi.x,
            hi.y,
            hi.z,
            hi.x - lo.x,
            hi.y - lo.y,
            hi.z - lo.z
        )?;
    }
    Ok(0)
}
