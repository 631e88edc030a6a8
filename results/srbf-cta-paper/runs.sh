#!/bin/bash
# The runs of results/srbf-cta-paper (from the repository root).
B=build/release/bench/srbf_cta_paper_bench
R=results/srbf-cta-paper
P="rank_view=8,rank_light=48,rank_vertex=24"
$B bunny $R/bunny.json "srbf_cta:clusters=9,$P" "afcpca:clusters=9,rank_view=8,segments=24,components=12" \
   "srbf_cta:clusters=9,$P,hooi_sweeps=4" "srbf_cta:clusters=9,$P,spread=1.5" "srbf_cta:clusters=9,$P,spread=0.5" > $R/bunny.log 2>&1
$B bunny-12k $R/bunny-12k.json "srbf_cta:clusters=34,$P" > $R/bunny-12k.log 2>&1
$B bunny $R/bunny-more.json "srbf_cta:clusters=9,$P,spread=0.75" "srbf_cta:clusters=9,rank_view=16,rank_light=48,rank_vertex=24" > $R/bunny-more.log 2>&1
# A rougher BRDF (more energy in the leading view terms), with and without the view truncation.
$B bunny $R/bunny-rough.json "srbf_cta:clusters=9,$P,brdf_roughness=0.6" "srbf_cta:clusters=9,rank_view=16,rank_light=48,rank_vertex=24,brdf_roughness=0.6" > $R/bunny-rough.log 2>&1
# The paper's vertex density on the largest bunny (47,960 vertices / 359 = 134 clusters), m = 0.6.
# Native build (README's default since issue 51), timed by /usr/bin/time -v.
/usr/bin/time -v build/native/bench/srbf_cta_paper_bench bunny-48k $R/bunny-48k.json "srbf_cta:clusters=134,$P,brdf_roughness=0.6" > $R/bunny-48k.log 2>&1
# Table 2's CPCA through the registered cpca backend on the declared BRDF-weighted input
# (signal=brdf implied): row CPCA of the 16 folded rows of every vertex, 2 passes per vector.
C="weights=float16,iterations_per_vector=2"
$B bunny $R/bunny-cpca.json "cpca:clusters=4,vectors=4,$C" "cpca:clusters=16,vectors=8,$C" \
   "cpca:clusters=32,vectors=12,$C" "cpca:clusters=16,vectors=8,$C,brdf_roughness=0.6" > $R/bunny-cpca.log 2>&1
