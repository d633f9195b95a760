//! A 3-D view of the simulated stock for the HTML report: the stock's top
//! surface as a height field, coloured by the material left over the part
//! (or by height when there is no part), drawn by a small self-contained
//! WebGL 2 script (drag to turn, wheel to zoom). Where WebGL is missing the
//! view says so and the page's 2-D map stands in for it.
//!
//! The data are embedded in the page (base64 little-endian `f32` heights and
//! RGB bytes per vertex): no network, no library.

use crate::svg::colormap_rgb;
use millplan_geom::TriMesh;
use millplan_sim::stock::Stock;
use std::fmt::Write;

/// The most vertices along either side of the view's grid.
pub const MAX_SIDE: usize = 240;

/// Colour of a point cut into the part (material left below zero).
const GOUGE: [u8; 3] = [200, 0, 170];

/// What the colours of a view mean: the quantity, its unit and the range the
/// colour scale spans (values beyond it take the end colours), next to the
/// full range of the data.
#[derive(Clone, Debug, PartialEq)]
pub struct Scale {
    pub quantity: &'static str,
    pub lo: f64,
    pub hi: f64,
    pub min: f64,
    pub max: f64,
}

/// The view's grid: heights and colours per vertex, row by row (x fastest).
#[derive(Clone, Debug)]
pub struct HeightField {
    pub nx: usize,
    pub ny: usize,
    pub x0: f64,
    pub y0: f64,
    pub step: f64,
    /// Per vertex, mm; NaN where there is no stock.
    pub z: Vec<f32>,
    pub rgb: Vec<u8>,
    pub scale: Scale,
}

/// The `p`-quantile (0..=1) of finite values, by sorting a copy.
pub fn quantile(values: &[f64], p: f64) -> Option<f64> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let k = ((v.len() - 1) as f64 * p.clamp(0.0, 1.0)).round() as usize;
    Some(v[k])
}

/// The colour scale of `values` from their 2nd to 98th percentile, so that a
/// few extreme values (a border of uncut stock, a spike) do not wash out the
/// rest; `None` when no value is finite.
pub fn robust_scale(quantity: &'static str, values: &[f64]) -> Option<Scale> {
    let lo = quantile(values, 0.02)?;
    let hi = quantile(values, 0.98)?;
    let min = quantile(values, 0.0)?;
    let max = quantile(values, 1.0)?;
    Some(Scale {
        quantity,
        lo,
        hi,
        min,
        max,
    })
}

/// The highest point of the part over each vertex of the grid (NaN where the
/// part is not below), by rasterising its facets at the vertices.
fn part_tops(mesh: &TriMesh, nx: usize, ny: usize, x0: f64, y0: f64, step: f64) -> Vec<f64> {
    let mut top = vec![f64::NAN; nx * ny];
    for t in 0..mesh.len() {
        let [a, b, c] = mesh.corners(t);
        let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        if det.abs() < 1e-12 {
            continue;
        }
        let lo_x = a.x.min(b.x).min(c.x);
        let hi_x = a.x.max(b.x).max(c.x);
        let lo_y = a.y.min(b.y).min(c.y);
        let hi_y = a.y.max(b.y).max(c.y);
        let i0 = ((lo_x - x0) / step).ceil().max(0.0) as usize;
        let j0 = ((lo_y - y0) / step).ceil().max(0.0) as usize;
        let i1 = (((hi_x - x0) / step).floor() + 1.0).clamp(0.0, nx as f64) as usize;
        let j1 = (((hi_y - y0) / step).floor() + 1.0).clamp(0.0, ny as f64) as usize;
        for j in j0..j1 {
            let y = y0 + j as f64 * step;
            for i in i0..i1 {
                let x = x0 + i as f64 * step;
                let u = ((x - a.x) * (c.y - a.y) - (c.x - a.x) * (y - a.y)) / det;
                let v = ((b.x - a.x) * (y - a.y) - (x - a.x) * (b.y - a.y)) / det;
                if u < -1e-9 || v < -1e-9 || u + v > 1.0 + 1e-9 {
                    continue;
                }
                let z = a.z + u * (b.z - a.z) + v * (c.z - a.z);
                let k = j * nx + i;
                if !(top[k] >= z) {
                    top[k] = z;
                }
            }
        }
    }
    top
}

/// The stock's top sampled on at most [`MAX_SIDE`] × [`MAX_SIDE`] vertices,
/// coloured by the material left over `part` (stock top − part top; below
/// zero: cut into the part, in magenta) or, without a part, by height.
pub fn height_field(stock: &Stock, part: Option<&TriMesh>) -> Option<HeightField> {
    let g = stock.grid;
    let stride = g.nx.max(g.ny).div_ceil(MAX_SIDE).max(1);
    let (nx, ny) = (g.nx.div_ceil(stride), g.ny.div_ceil(stride));
    let step = g.res * stride as f64;
    let (x0, y0) = (g.cx(0), g.cy(0));
    let mut z = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let t = stock.top((i * stride).min(g.nx - 1), (j * stride).min(g.ny - 1));
            z.push(t.map_or(f32::NAN, |t| t as f32));
        }
    }
    let (values, quantity): (Vec<f64>, &'static str) = match part {
        Some(mesh) => {
            let tops = part_tops(mesh, nx, ny, x0, y0, step);
            let left = z
                .iter()
                .zip(&tops)
                .map(|(s, p)| f64::from(*s) - p)
                .collect();
            (left, "material left over the part (mm)")
        }
        None => (z.iter().map(|v| f64::from(*v)).collect(), "height z (mm)"),
    };
    let scale = robust_scale(quantity, &values)?;
    let span = (scale.hi - scale.lo).max(1e-12);
    let cut_into = part.is_some();
    let mut rgb = Vec::with_capacity(3 * values.len());
    for v in &values {
        let c = if !v.is_finite() {
            [200, 200, 200]
        } else if cut_into && *v < -1e-3 {
            GOUGE
        } else {
            colormap_rgb((v - scale.lo) / span)
        };
        rgb.extend_from_slice(&c);
    }
    Some(HeightField {
        nx,
        ny,
        x0,
        y0,
        step,
        z,
        rgb,
        scale,
    })
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[((n >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A length to the micrometre, never "-0.000".
fn mm(v: f64) -> String {
    let t = format!("{v:.3}");
    if t == "-0.000" {
        "0.000".into()
    } else {
        t
    }
}

/// The colour bar and the scale's words under the canvas.
fn legend(h: &mut String, s: &Scale) {
    h.push_str("<div class=\"view3d-legend\" style=\"display:flex;align-items:center;gap:8px;font-size:12px\">");
    let _ = write!(h, "<span>{}</span>", mm(s.lo));
    h.push_str("<span style=\"display:inline-block;width:240px;height:12px;background:linear-gradient(to right");
    for k in 0..=8 {
        let [r, g, b] = colormap_rgb(f64::from(k) / 8.0);
        let _ = write!(h, ",rgb({r},{g},{b})");
    }
    h.push_str(")\"></span>");
    let _ = write!(
        h,
        "<span>{}</span><span>{}; the scale spans the 2nd to 98th percentile, all values {} to {}; beyond it the end colours",
        mm(s.hi),
        s.quantity,
        mm(s.min),
        mm(s.max)
    );
    if s.quantity.starts_with("material") {
        let [r, g, b] = GOUGE;
        let _ = write!(
            h,
            "; <span style=\"color:rgb({r},{g},{b})\">magenta</span>: cut into the part"
        );
    }
    h.push_str("; grey: no stock or no part below.</span></div>");
}

/// The view as an HTML fragment: a canvas, its legend and the script that
/// draws it. `id` names the canvas (one per page).
pub fn fragment(id: &str, f: &HeightField) -> String {
    let mut z = Vec::with_capacity(4 * f.z.len());
    for v in &f.z {
        z.extend_from_slice(&v.to_le_bytes());
    }
    let mut h = String::new();
    let _ = write!(
        h,
        "<div class=\"view3d\"><canvas id=\"{id}\" width=\"900\" height=\"560\" style=\"width:900px;max-width:100%;border:1px solid #ccc;background:#fff;cursor:grab\" \
         data-nx=\"{}\" data-ny=\"{}\" data-x0=\"{}\" data-y0=\"{}\" data-step=\"{}\" data-z=\"{}\" data-rgb=\"{}\"></canvas>\
         <p id=\"{id}-nogl\" style=\"display:none;color:#a15c00\">This browser offers no WebGL 2: the 2-D map below shows the same stock.</p>",
        f.nx,
        f.ny,
        f.x0,
        f.y0,
        f.step,
        base64(&z),
        base64(&f.rgb)
    );
    legend(&mut h, &f.scale);
    let _ = write!(
        h,
        "<p style=\"font-size:12px;color:#555\">Drag to turn, wheel to zoom. X red, Y green, Z up.</p></div><script>{}</script>",
        SCRIPT.replace("__ID__", id)
    );
    h
}

/// The drawing script: WebGL 2, triangles of the height field with flat
/// shading from screen-space derivatives, orbit and zoom. On success the
/// canvas carries `data-rendered="webgl2"` and `data-painted` (the share of
/// pixels the stock covers, from a read-back), which a headless test reads.
const SCRIPT: &str = r#"(function(){
var cv=document.getElementById('__ID__');
var gl=cv.getContext('webgl2',{preserveDrawingBuffer:true,antialias:true});
if(!gl){document.getElementById('__ID__-nogl').style.display='block';cv.style.display='none';cv.dataset.rendered='none';return;}
function b64(s){var b=atob(s),u=new Uint8Array(b.length);for(var i=0;i<b.length;i++)u[i]=b.charCodeAt(i);return u;}
var nx=+cv.dataset.nx,ny=+cv.dataset.ny,x0=+cv.dataset.x0,y0=+cv.dataset.y0,st=+cv.dataset.step;
var z=new Float32Array(b64(cv.dataset.z).buffer),rgb=b64(cv.dataset.rgb);
var zmin=Infinity,zmax=-Infinity;for(var k=0;k<z.length;k++){if(z[k]===z[k]){zmin=Math.min(zmin,z[k]);zmax=Math.max(zmax,z[k]);}}
if(!(zmin<=zmax)){zmin=0;zmax=1;}
var cx=x0+st*(nx-1)/2,cy=y0+st*(ny-1)/2,cz=(zmin+zmax)/2;
var R=Math.max(st*nx,st*ny,zmax-zmin)*0.62;
var pos=new Float32Array(nx*ny*3),col=new Uint8Array(nx*ny*3);
for(var j=0;j<ny;j++)for(var i=0;i<nx;i++){var k=j*nx+i,h=z[k];pos[3*k]=x0+i*st-cx;pos[3*k+1]=y0+j*st-cy;pos[3*k+2]=(h===h?h:zmin)-cz;col.set(rgb.subarray(3*k,3*k+3),3*k);}
var idx=[];for(var j=0;j+1<ny;j++)for(var i=0;i+1<nx;i++){var a=j*nx+i,b=a+1,c=a+nx,d=c+1;if(z[a]===z[a]&&z[b]===z[b]&&z[c]===z[c]&&z[d]===z[d]){idx.push(a,b,d,a,d,c);}}
idx=new Uint32Array(idx);
function sh(t,s){var o=gl.createShader(t);gl.shaderSource(o,s);gl.compileShader(o);if(!gl.getShaderParameter(o,gl.COMPILE_STATUS))throw new Error(gl.getShaderInfoLog(o));return o;}
var pr=gl.createProgram();
gl.attachShader(pr,sh(gl.VERTEX_SHADER,'#version 300 es\nin vec3 p;in vec3 c;uniform mat4 m;out vec3 vc;out vec3 vp;void main(){vc=c;vp=p;gl_Position=m*vec4(p,1.0);}'));
gl.attachShader(pr,sh(gl.FRAGMENT_SHADER,'#version 300 es\nprecision highp float;in vec3 vc;in vec3 vp;uniform vec3 l;out vec4 o;void main(){vec3 n=normalize(cross(dFdx(vp),dFdy(vp)));float d=0.35+0.65*abs(dot(n,l));o=vec4(vc*d,1.0);}'));
gl.linkProgram(pr);if(!gl.getProgramParameter(pr,gl.LINK_STATUS))throw new Error(gl.getProgramInfoLog(pr));
gl.useProgram(pr);
function buf(t,d){var b=gl.createBuffer();gl.bindBuffer(t,b);gl.bufferData(t,d,gl.STATIC_DRAW);return b;}
var va=gl.createVertexArray();gl.bindVertexArray(va);
buf(gl.ARRAY_BUFFER,pos);var lp=gl.getAttribLocation(pr,'p');gl.enableVertexAttribArray(lp);gl.vertexAttribPointer(lp,3,gl.FLOAT,false,0,0);
buf(gl.ARRAY_BUFFER,col);var lc=gl.getAttribLocation(pr,'c');gl.enableVertexAttribArray(lc);gl.vertexAttribPointer(lc,3,gl.UNSIGNED_BYTE,true,0,0);
buf(gl.ELEMENT_ARRAY_BUFFER,idx);
var um=gl.getUniformLocation(pr,'m'),ul=gl.getUniformLocation(pr,'l');
var az=-0.6,el=0.75,zoom=1.0;
function mul(a,b){var r=new Float32Array(16);for(var i=0;i<4;i++)for(var j=0;j<4;j++){var s=0;for(var k=0;k<4;k++)s+=a[k*4+j]*b[i*4+k];r[i*4+j]=s;}return r;}
function draw(){
var w=cv.width,h=cv.height,ca=Math.cos(az),sa=Math.sin(az),ce=Math.cos(el),se=Math.sin(el);
var rz=new Float32Array([ca,-sa*ce,sa*se,0, sa,ca*ce,-ca*se,0, 0,se,ce,0, 0,0,0,1]);
var s=zoom/R,asp=w/h;
var pj=new Float32Array([s/asp,0,0,0, 0,s,0,0, 0,0,-s*0.5,0, 0,0,0,1]);
gl.viewport(0,0,w,h);gl.clearColor(1,1,1,1);gl.clear(gl.COLOR_BUFFER_BIT|gl.DEPTH_BUFFER_BIT);gl.enable(gl.DEPTH_TEST);
gl.uniformMatrix4fv(um,false,mul(pj,rz));gl.uniform3f(ul,0.3,0.4,0.87);
gl.drawElements(gl.TRIANGLES,idx.length,gl.UNSIGNED_INT,0);}
draw();
var px=new Uint8Array(cv.width*cv.height*4);gl.readPixels(0,0,cv.width,cv.height,gl.RGBA,gl.UNSIGNED_BYTE,px);
var painted=0;for(var k=0;k<px.length;k+=4){if(px[k]<250||px[k+1]<250||px[k+2]<250)painted++;}
cv.dataset.painted=(painted/(cv.width*cv.height)).toFixed(4);cv.dataset.rendered='webgl2';
var drag=null;
cv.addEventListener('mousedown',function(e){drag=[e.clientX,e.clientY];cv.style.cursor='grabbing';});
window.addEventListener('mouseup',function(){drag=null;cv.style.cursor='grab';});
window.addEventListener('mousemove',function(e){if(!drag)return;az-=(e.clientX-drag[0])*0.01;el=Math.max(0.05,Math.min(1.55,el-(e.clientY-drag[1])*0.01));drag=[e.clientX,e.clientY];draw();});
cv.addEventListener('wheel',function(e){e.preventDefault();zoom=Math.max(0.2,Math.min(20,zoom*Math.exp(-e.deltaY*0.001)));draw();},{passive:false});
})();"#;

#[cfg(test)]
mod tests {
    use super::*;
    use millplan_geom::DVec3;

    #[test]
    fn base64_matches_the_rfc_4648_examples() {
        assert_eq!(base64(b""), "");
        assert_eq!(base64(b"f"), "Zg==");
        assert_eq!(base64(b"fo"), "Zm8=");
        assert_eq!(base64(b"foo"), "Zm9v");
        assert_eq!(base64(b"foobar"), "Zm9vYmFy");
    }

    #[test]
    fn robust_scale_ignores_a_thin_border() {
        // 98.5 % of the values near 0.1 mm, a 1.5 % border of 5 mm uncut stock.
        let mut v: Vec<f64> = (0..985).map(|i| 0.1 + 0.001 * f64::from(i % 10)).collect();
        v.extend(std::iter::repeat_n(5.0, 15));
        let s = robust_scale("m", &v).expect("finite");
        assert!(s.hi < 0.2, "{s:?}");
        assert_eq!(s.max, 5.0);
        assert!(robust_scale("m", &[f64::NAN]).is_none());
    }

    #[test]
    fn part_tops_interpolate_a_sloped_facet_and_keep_the_highest() {
        // Two facets over [0,2]²: a plane z = x, and above it z = 5 on x ≤ 1.
        let mesh = TriMesh::from_soup(&[
            [
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(2.0, 0.0, 2.0),
                DVec3::new(2.0, 2.0, 2.0),
            ],
            [
                DVec3::new(0.0, 0.0, 0.0),
                DVec3::new(2.0, 2.0, 2.0),
                DVec3::new(0.0, 2.0, 0.0),
            ],
            [
                DVec3::new(0.0, 0.0, 5.0),
                DVec3::new(1.0, 0.0, 5.0),
                DVec3::new(0.0, 1.0, 5.0),
            ],
        ])
        .0;
        let t = part_tops(&mesh, 3, 3, 0.0, 0.0, 1.0);
        assert_eq!(t[4], 1.0); // (1, 1): on the plane only
        assert_eq!(t[2], 2.0); // (2, 0)
        assert_eq!(t[0], 5.0); // (0, 0): the higher facet
        assert_eq!(t[1], 5.0); // (1, 0): on the higher facet's edge
    }

    #[test]
    fn a_stock_over_its_part_colours_every_vertex_and_embeds_its_data() {
        let stock = Stock::block(DVec3::new(0.0, 0.0, 0.0), DVec3::new(30.0, 20.0, 10.0), 0.5);
        let part = TriMesh::from_soup(&[
            [
                DVec3::new(-1.0, -1.0, 9.0),
                DVec3::new(31.0, -1.0, 9.0),
                DVec3::new(31.0, 21.0, 9.0),
            ],
            [
                DVec3::new(-1.0, -1.0, 9.0),
                DVec3::new(31.0, 21.0, 9.0),
                DVec3::new(-1.0, 21.0, 9.0),
            ],
        ])
        .0;
        let f = height_field(&stock, Some(&part)).expect("a field");
        assert_eq!((f.nx, f.ny), (60, 40));
        assert_eq!(f.rgb.len(), 3 * f.z.len());
        assert!(
            (f.scale.lo - 1.0).abs() < 1e-6 && (f.scale.hi - 1.0).abs() < 1e-6,
            "{:?}",
            f.scale
        );
        let html = fragment("v", &f);
        assert!(html.contains("data-nx=\"60\"") && html.contains("getContext('webgl2'"));
        assert!(!html.contains("__ID__"));
    }
}
