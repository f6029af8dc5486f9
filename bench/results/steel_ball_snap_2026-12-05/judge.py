import h5py, numpy as np, sys
f=h5py.File(sys.argv[1])
o=f['observables']
tot = sum(np.array(o[k]['value']) for k in ['kinetic_energy','magnetic_energy','gravity_energy'])
mag = np.array(o['magnetic_energy']['value'])
sub=np.array(o['substeps']['value']).sum()
P=f['particles/bodies']; v=np.array(P['velocity/value'])
# largest rise above running min, relative to |min magnetic energy| (binding)
runmin=np.minimum.accumulate(tot); rise=(tot-runmin).max()
bind=abs(mag.min())
print("%-22s %-18s sub %5d rise %5.1f%% of %.1f mJ  vmax_last10 %.3f" % (sys.argv[2], sys.argv[3], sub, 100*rise/bind, bind*1e3, np.linalg.norm(v[-10:],axis=2).max()))
