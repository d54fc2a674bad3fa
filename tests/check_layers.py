#!/usr/bin/env python3
"""Layering of the engine's component targets (engine/CMakeLists.txt, issue 19): no
target's sources include, directly or through other headers, a header of a target it does
not link, or a third-party header it does not link. A header belongs to the target that
defines what it declares (the table below); a new header needs an entry, so that its
layer is a decision. The link test (tests/consumers/sim_only.cpp) cannot see header-only
libraries such as nlohmann-json; this can. Usage: check_layers.py SOURCE_DIR"""
import re,pathlib,sys
root=pathlib.Path(sys.argv[1] if len(sys.argv)>1 else '.')/'engine'
cm=(root/'CMakeLists.txt').read_text()
targets={}
for m in re.finditer(r'kodawari_component\((\w+)\n(.*?)\)',cm,re.S):
    targets[m.group(1)]=m.group(2).split()
# What each target links (itself included), as engine/CMakeLists.txt says.
links={'sim':{'sim'},'vulkan':{'vulkan','sim'},'io':{'io','sim'},'render':{'render','vulkan','io','sim'},'engine':{'engine','render','vulkan','io','sim'}}
# The third-party headers each may include (a prefix of the include).
third={'sim':set(),'vulkan':{'vulkan'},'io':{'tiny_gltf','nlohmann'},'render':{'vulkan','stb'},'engine':{'vulkan'}}
# owner of each public/internal header: the target that defines what it declares
own={}
def o(pat,t):
    for f in root.glob(pat): own[str(f.relative_to(root))]=t
for pat,t in [('include/kodawari/*.hpp','sim'),('include/kodawari/birds/*.hpp','sim'),('include/kodawari/rods/*.hpp','sim'),('core/*.hpp','sim'),('birds/*.hpp','sim'),
              ('backends/backends.hpp','sim'),('backends/pose_backends.hpp','sim'),('backends/device_backends.hpp','vulkan'),('compute/*.hpp','vulkan'),('gpu/*.hpp','vulkan'),
              ('scene/*.hpp','io'),('export/*.hpp','io'),('gltf/*.hpp','io'),('render/*.hpp','render'),('include/kodawari/render/*.hpp','render')]:
    o(pat,t)
for h,t in {'gltf/character.hpp':'sim','gltf/pose_instance.hpp':'sim','gltf/chains.hpp':'io','gltf/vrm.hpp':'io','gltf/rig_scene.hpp':'io','gltf/import.hpp':'io',
            'backend_factory.hpp':'vulkan','crowd_animator.hpp':'vulkan','gpu_info.hpp':'vulkan','scene.hpp':'io','rod_scene.hpp':'io','export.hpp':'io','scene_edit.hpp':'io','simulation.hpp':'engine'}.items():
    own['include/kodawari/'+h]=t
def resolve(inc,src):
    for base in [root/'include', root, src.parent]:
        p=base/inc
        if p.exists(): return str(p.resolve().relative_to(root.resolve())) if str(p.resolve()).startswith(str(root.resolve())) else None
    return None
bad=0
def scan(f,t,seen):
    global bad
    if f in seen: return
    seen.add(f)
    for inc in re.findall(r'#include\s*[<"]([^>"]+)[>"]',f.read_text()):
        if any(inc.startswith(x) for x in third[t]) or inc.startswith(('tiny_gltf','nlohmann','vulkan/','stb/')):
            if not any(inc.startswith(x) for x in third[t]): print(f'{t}: {f} includes {inc}'); bad+=1
            continue
        if inc.startswith('kodawari/shared/'): continue
        r=resolve(inc,f)
        if r is None: continue
        ow=own.get(r)
        if ow is None: print('unowned',r); bad+=1; continue
        if ow not in links[t]: print(f'{t}: {f} includes {inc} ({ow})'); bad+=1
        scan(root/r,t,seen)
for t,srcs in targets.items():
    for s in srcs:
        if s.endswith('.cpp'): scan(root/s,t,set())
print('checked',{t:len(s) for t,s in targets.items()},'problems',bad)
sys.exit(1 if bad else 0)
